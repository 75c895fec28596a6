"""Does a Ray server answer at an address, and does it take this process's token?

Run by :mod:`eval.ray_cluster` in a child process (``python -m eval.ray_probe KIND
HOST:PORT``), so that the parent can bound the check by killing the child: Ray's own
connection retries for minutes inside native code, where a signal cannot stop it. KIND is
``client`` (a Ray Client server: one ``ClusterInfo`` ping over gRPC, with Ray's token
interceptor when token authentication is on) or ``gcs`` (the head's GCS: Ray's own GCS
client, which fetches the cluster's id). The answer is one JSON line on stdout,
``{"status": S, "detail": D}``:

- ``ok``: the server answered and accepted the request;
- ``auth``: it refused the request for its token (missing or wrong);
- ``not_ray``: something answered, but not a server of that kind (another Ray port);
- ``no_answer``: nothing answered in time;
- ``error``: anything else (``detail`` says what, one line).

The token itself is never read or printed here: Ray's own code sends it.
"""

from __future__ import annotations

import json
import sys

#: Seconds each gRPC wait of the client ping may take (the parent bounds the whole).
CLIENT_WAIT_S = 10.0


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())[:300] or type(exc).__name__


def probe_client(hostport: str, wait_s: float = CLIENT_WAIT_S) -> tuple[str, str]:
    """Ping the Ray Client server at ``hostport``."""
    import grpc
    from ray.core.generated import ray_client_pb2, ray_client_pb2_grpc

    try:
        from ray._private.grpc_utils import init_grpc_channel  # Ray >= 2.52: adds the token
    except ImportError:
        init_grpc_channel = grpc.insecure_channel
    channel = init_grpc_channel(hostport)
    try:
        grpc.channel_ready_future(channel).result(timeout=wait_s)
        stub = ray_client_pb2_grpc.RayletDriverStub(channel)
        stub.ClusterInfo(ray_client_pb2.ClusterInfoRequest(
            type=ray_client_pb2.ClusterInfoType.PING), timeout=wait_s)
    except grpc.FutureTimeoutError:
        return "no_answer", f"no gRPC answer within {wait_s:g} s"
    except grpc.RpcError as exc:
        code = exc.code()
        if code == grpc.StatusCode.UNAUTHENTICATED:
            return "auth", exc.details() or "unauthenticated"
        if code == grpc.StatusCode.UNIMPLEMENTED:
            return "not_ray", "the server there has no Ray Client service"
        if code in (grpc.StatusCode.UNAVAILABLE, grpc.StatusCode.DEADLINE_EXCEEDED):
            return "no_answer", exc.details() or code.name
        return "error", f"{code.name}: {exc.details()}"
    finally:
        channel.close()
    return "ok", ""


def probe_gcs(hostport: str) -> tuple[str, str]:
    """Fetch the cluster's id from the GCS at ``hostport`` (Ray's GCS client)."""
    import ray
    from ray._raylet import GcsClient

    try:
        GcsClient(address=hostport)
    except Exception as exc:
        auth_error = getattr(ray.exceptions, "AuthenticationError", ())
        text = _one_line(exc)
        if auth_error and isinstance(exc, auth_error):
            return "auth", text
        if "Method not found" in text:
            return "not_ray", "the server there has no GCS service"
        if "Timed out" in text or "unavailable" in text.lower():
            return "no_answer", text
        return "error", text
    return "ok", ""


def main(argv: list[str]) -> int:
    kind, hostport = argv
    try:
        status, detail = probe_client(hostport) if kind == "client" else probe_gcs(hostport)
    except Exception as exc:  # reported to the parent, which prints one line
        status, detail = "error", f"{type(exc).__name__}: {_one_line(exc)}"
    print(json.dumps({"status": status, "detail": detail}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
