"""Connecting to an existing Ray cluster (``--address``): the two address forms, Ray's
token authentication, and a bounded check that the cluster is there before Ray connects.

Address forms (see docs/guides/ray-cluster.md):

- ``ray://HOST:PORT``: through Ray Client, the head's client server (``ray start --head
  --ray-client-server-port 10001``); needs ``ray[client]`` (the project's ``ray`` extra).
  Works from any machine that reaches that one port.
- ``HOST:PORT``: the head's GCS (``ray start --head --port 6379``), from a machine of the
  cluster's network (the driver joins the cluster's processes directly).

Token authentication (Ray >= 2.52, ``RAY_AUTH_MODE=token`` on the cluster): the token is
Ray's own, looked up in Ray's order: ``RAY_AUTH_TOKEN``, else the file named by
``RAY_AUTH_TOKEN_PATH``, else ``~/.ray/auth_token``. When ``RAY_AUTH_MODE`` is unset and a
token is found, token mode is switched on for this process (as ``ray start`` does for a
head that finds one): an explicit address never does that in Ray itself, so without it a
cluster with authentication on refuses the driver. ``RAY_AUTH_MODE=disabled`` sends no
token. The token is never printed, never given to the workers (the runtime environment
carries only PYTHONPATH and the BLAS thread counts) and never written into any result;
this module only checks that it is there.

Ray's own connection retries for many minutes when nothing answers, inside native code that
a signal cannot interrupt. So before ``ray.init`` the address gets a bounded check
(:data:`LIMITS`): a TCP connection, then a child process (:mod:`eval.ray_probe`) that asks
the server one question with the token and is killed if it takes too long. Every failure is
a one-line :class:`~upm.core.errors.UsageError` naming the address and the fix.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import subprocess
import sys
from dataclasses import dataclass, replace
from pathlib import Path

from upm.core.errors import UsageError

#: The token file Ray reads when neither environment variable is set.
DEFAULT_TOKEN_FILE = Path("~") / ".ray" / "auth_token"
#: Ray Client's specific server can die while it starts (a gRPC fork race in Ray's proxy,
#: ray-project/ray#63202): the messages ``ray.init`` fails with then (the proxy's answer,
#: and psutil's when the proxy looks at the server process after it died, seen on a
#: loaded two-core machine).
CLIENT_START_FAILURES = ("Starting Ray client server failed",
                         "PID still exists but it's a zombie")


@dataclass(frozen=True)
class ConnectLimits:
    """How long the check before connecting may take (about 30 s at most in all).

    Attributes
    ----------
    reach_s : float
        The TCP connection to the address.
    answer_s : float
        The probe process: Ray's handshake with the server and the token check.
    client_start_retries : int
        New tries when Ray Client's server died while starting (:data:`CLIENT_START_FAILURES`).
    """

    reach_s: float = 8.0
    answer_s: float = 20.0
    client_start_retries: int = 1


LIMITS = ConnectLimits()


@dataclass(frozen=True)
class ClusterAddress:
    """A parsed ``--address``.

    Attributes
    ----------
    text : str
        As given (what ``ray.init`` gets).
    client : bool
        ``ray://``: through Ray Client; else the GCS.
    host : str
    port : int
    """

    text: str
    client: bool
    host: str
    port: int
    #: Where Ray connects for it (a GCS address on this machine's loopback becomes the
    #: node's own IP address in Ray: the check must ask the same place).
    target: str | None = None

    @property
    def label(self) -> str:
        return f"--address {self.text}"

    @property
    def hostport(self) -> str:
        host = self.target or self.host
        return f"[{host}]:{self.port}" if ":" in host else f"{host}:{self.port}"

    @property
    def where(self) -> str:
        """:attr:`hostport`, saying so when Ray connects elsewhere than the host given."""
        return self.hostport + (f" (where Ray connects for {self.host})" if self.target else "")

    @property
    def server(self) -> str:
        return "Ray Client server" if self.client else "Ray GCS"


def parse_address(text: str) -> ClusterAddress:
    """``ray://HOST:PORT`` or ``HOST:PORT`` (an IPv6 host in brackets)."""
    form = ("give ray://HOST:PORT (Ray Client, port 10001 by default) or HOST:PORT (the "
            "head's GCS, port 6379 by default)")
    client = text.startswith("ray://")
    rest = text[len("ray://"):] if client else text
    if "://" in rest or "/" in rest:
        raise UsageError(f"--address {text}: {form}")
    host, sep, port_text = rest.rpartition(":")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    if not sep or not host or not port_text.isdigit() or not 0 < int(port_text) < 65536:
        raise UsageError(f"--address {text}: {form}")
    return ClusterAddress(text=text, client=client, host=host, port=int(port_text))


def ray_target(address: ClusterAddress) -> ClusterAddress:
    """The address with the host Ray itself connects to: for the GCS form, a loopback
    host is replaced by the node's IP address as ``ray.init`` does (Ray's own function);
    a ``ray://`` address is used as given."""
    if address.client:
        return address
    try:
        from ray._private.services import resolve_ip_for_localhost
    except ImportError:
        return address
    host = resolve_ip_for_localhost(address.host)
    return address if host == address.host else replace(address, target=host)


# --- the token ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Auth:
    """How the connection authenticates.

    Attributes
    ----------
    mode : str
        ``RAY_AUTH_MODE`` as the connection uses it (``"token"``, ``"disabled"``, ...).
    source : str or None
        Where the token comes from (``RAY_AUTH_TOKEN``, ``RAY_AUTH_TOKEN_PATH (FILE)`` or
        the default file), never the token; None if there is none.
    switched_on : bool
        ``RAY_AUTH_MODE`` was unset and is set to ``token`` for the connection.
    """

    mode: str
    source: str | None
    switched_on: bool


def _holds_text(path: Path) -> bool:
    try:
        return bool(path.read_text(encoding="utf-8", errors="replace").strip())
    except OSError:
        return False


def token_source() -> str | None:
    """Where Ray would take the token from (Ray's order), or None.

    Raises
    ------
    UsageError
        ``RAY_AUTH_TOKEN_PATH`` names a missing, unreadable or empty file (Ray aborts the
        process on that).
    """
    if os.environ.get("RAY_AUTH_TOKEN", "").strip():
        return "RAY_AUTH_TOKEN"
    named = os.environ.get("RAY_AUTH_TOKEN_PATH")
    if named:
        if not _holds_text(Path(named).expanduser()):
            raise UsageError(f"RAY_AUTH_TOKEN_PATH={named}: no such file, or unreadable or "
                             "empty: point it at a file holding the cluster's token, or unset "
                             "it")
        return f"RAY_AUTH_TOKEN_PATH ({named})"
    if _holds_text(DEFAULT_TOKEN_FILE.expanduser()):
        return str(DEFAULT_TOKEN_FILE)
    return None


def resolve_auth() -> Auth:
    """The authentication the connection will use (see the module's docstring)."""
    mode = os.environ.get("RAY_AUTH_MODE")
    if mode is not None and mode.strip().lower() == "disabled":
        return Auth(mode="disabled", source=None, switched_on=False)
    source = token_source()
    if mode is None:
        return Auth(mode="token" if source else "disabled", source=source,
                    switched_on=source is not None)
    if mode.strip().lower() == "token" and source is None:
        raise UsageError("RAY_AUTH_MODE=token but no token was found: put the cluster's token "
                         f"(`ray get-auth-token` on the head prints it) in {DEFAULT_TOKEN_FILE},"
                         " or name a file holding it in RAY_AUTH_TOKEN_PATH")
    return Auth(mode=mode.strip().lower(), source=source, switched_on=False)


def _refresh_ray_config() -> None:
    """Make an already loaded Ray read RAY_AUTH_MODE again (what Ray does when it switches
    token mode on itself)."""
    try:
        from ray._raylet import Config
    except ImportError:
        return
    with contextlib.suppress(AttributeError):
        Config.initialize("")


@contextlib.contextmanager
def auth_environment(auth: Auth):
    """``RAY_AUTH_MODE=token`` in this process while connected, if :func:`resolve_auth`
    switched it on; the environment as it was afterwards."""
    if not auth.switched_on:
        yield
        return
    os.environ["RAY_AUTH_MODE"] = "token"
    _refresh_ray_config()
    try:
        yield
    finally:
        os.environ.pop("RAY_AUTH_MODE", None)
        _refresh_ray_config()


# --- the check before connecting ------------------------------------------------------------


def check_reachable(address: ClusterAddress, limits: ConnectLimits | None = None) -> None:
    """A TCP connection to the address, or a one-line UsageError saying why not."""
    limits = limits or LIMITS
    which = ("client server port (--ray-client-server-port, 10001 by default)" if address.client
             else "GCS port (--port, 6379 by default)")
    try:
        socket.getaddrinfo(address.host, address.port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        raise UsageError(f"{address.label}: cannot resolve the host {address.host!r} "
                         f"({exc.strerror}): give the head's host name or IP address") from None
    try:
        with socket.create_connection((address.target or address.host, address.port),
                                      timeout=limits.reach_s):
            pass
    except ConnectionRefusedError:
        raise UsageError(f"{address.label}: nothing listens at {address.where} (connection "
                         f"refused): is the head running there (ray start --head), and is "
                         f"{address.port} its {which}?") from None
    except TimeoutError:
        raise UsageError(f"{address.label}: no answer from {address.where} within "
                         f"{limits.reach_s:g} s: is the head running, and can this machine "
                         "reach it (network, firewall)?") from None
    except OSError as exc:
        raise UsageError(f"{address.label}: cannot reach {address.where}: "
                         f"{exc.strerror or exc}") from None


def probe(address: ClusterAddress, auth: Auth,
          limits: ConnectLimits | None = None) -> tuple[str, str]:
    """Ask the server one question in a child process (:mod:`eval.ray_probe`), killed after
    ``limits.answer_s``: ``(status, detail)``."""
    limits = limits or LIMITS
    root = str(Path(__file__).resolve().parent.parent)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([root, *filter(None, [env.get("PYTHONPATH")])])
    if auth.switched_on:
        env["RAY_AUTH_MODE"] = "token"
    command = [sys.executable, "-m", "eval.ray_probe", "client" if address.client else "gcs",
               address.hostport]
    try:
        done = subprocess.run(command, env=env, capture_output=True, text=True,
                              timeout=limits.answer_s, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return "no_answer", f"no answer within {limits.answer_s:g} s"
    try:
        answer = json.loads(done.stdout.strip().splitlines()[-1])
        return str(answer["status"]), str(answer["detail"])
    except (IndexError, ValueError, KeyError, TypeError):
        last = (done.stderr.strip().splitlines() or [""])[-1][:300]
        return "error", f"the check ended with exit code {done.returncode}: {last}"


def explain(address: ClusterAddress, auth: Auth, status: str, detail: str) -> str:
    """The one-line message for a failed :func:`probe`."""
    get_token = "`ray get-auth-token` on the head prints it"
    if status == "auth":
        if auth.mode == "token":
            return (f"{address.label}: the cluster refused the authentication token from "
                    f"{auth.source}: use the cluster's token ({get_token})")
        if os.environ.get("RAY_AUTH_MODE", "").strip().lower() == "disabled":
            return (f"{address.label}: the cluster asks for Ray's authentication token and "
                    "RAY_AUTH_MODE=disabled sends none: unset RAY_AUTH_MODE, with the "
                    f"cluster's token in {DEFAULT_TOKEN_FILE} or RAY_AUTH_TOKEN_PATH")
        return (f"{address.label}: the cluster asks for Ray's authentication token and none "
                f"was found: put the cluster's token ({get_token}) in {DEFAULT_TOKEN_FILE}, "
                "or name a file holding it in RAY_AUTH_TOKEN_PATH")
    if status == "not_ray":
        other = (f"{address.hostport} (the GCS form, without ray://)" if address.client
                 else f"ray://{address.hostport} (the Ray Client form)")
        return (f"{address.label}: {address.hostport} answers but is not a {address.server} "
                f"({detail}); if it is the head's other port, give {other}")
    if status == "no_answer":
        return f"{address.label}: no {address.server} answered at {address.where} ({detail})"
    return f"{address.label}: cannot connect to the Ray cluster: {detail}"


_CHECKED: set[tuple] = set()


def check_cluster(text: str, limits: ConnectLimits | None = None) -> tuple[ClusterAddress, Auth]:
    """Everything before ``ray.init``: the address's form, Ray Client installed (for
    ``ray://``), the token, the server answering and taking the token. Checked once per
    address and authentication in a process.

    Raises
    ------
    UsageError
        One line naming the address, what is wrong and the fix.
    """
    limits = limits or LIMITS
    address = ray_target(parse_address(text))
    if address.client:
        try:
            import grpc  # noqa: F401  (what ray[client] adds)
        except ImportError:
            raise UsageError(f"{address.label}: a ray:// address goes through Ray Client, "
                             "which is not installed: pip install -e '.[ray]' (or pip install "
                             f"'ray[client]'), or give the head's GCS address "
                             f"({address.host}:6379) from a machine of the cluster") from None
    auth = resolve_auth()
    key = (address, auth)
    if key in _CHECKED:
        return address, auth
    check_reachable(address, limits)
    status, detail = probe(address, auth, limits)
    if status != "ok":
        raise UsageError(explain(address, auth, status, detail))
    _CHECKED.add(key)
    return address, auth


def is_client_start_failure(exc: BaseException) -> bool:
    """Whether ``ray.init`` failed because Ray Client's server died while it started
    (:data:`CLIENT_START_FAILURES`): worth one more try."""
    return any(marker in str(exc) for marker in CLIENT_START_FAILURES)


@contextlib.contextmanager
def cluster_connection(ray, text: str, options: dict, limits: ConnectLimits | None = None):
    """Connected to the cluster at ``text`` for the body: :func:`check_cluster`, then
    ``ray.init`` (once more if Ray Client's server died while starting), token mode kept on
    while connected if it was switched on; ``ray.shutdown`` at the end.

    Raises
    ------
    UsageError
        One line naming the address, if the check or ``ray.init`` fails.
    """
    limits = limits or LIMITS
    address, auth = check_cluster(text, limits)
    with auth_environment(auth):
        for attempt in range(1 + limits.client_start_retries):
            try:
                ray.init(address=address.text, **options)
                break
            except Exception as exc:  # every way ray.init fails: one line naming the address
                last = (str(exc).strip().splitlines() or [type(exc).__name__])[-1][:300]
                transient = address.client and is_client_start_failure(exc)
                with contextlib.suppress(Exception):
                    ray.shutdown()
                if not (transient and attempt < limits.client_start_retries):
                    raise UsageError(f"{address.label}: cannot connect to the Ray cluster: "
                                     f"{last}") from None
        try:
            yield
        finally:
            ray.shutdown()
