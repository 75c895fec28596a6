"""``--address`` before any cluster is involved: a malformed address, nothing listening,
something listening that is not Ray, a ``ray://`` address without Ray Client, a token
setting that cannot work. Each is one line on stderr naming the address (or the variable)
and the fix, exit 2, nothing written, and quick (the check is bounded, where Ray's own
connection retries for many minutes). With a cluster: tests/test_ray_cluster.py."""

from __future__ import annotations

import os
import socket
import sys
import threading

import pytest

pytest.importorskip("ray")

import eval.ray_cluster as ray_cluster  # noqa: E402
from eval.ray_cluster import ConnectLimits, parse_address  # noqa: E402
from upm.core.errors import UsageError  # noqa: E402


def _run(tmp_path, capsys, *args, command="eval"):
    from upm.cli import main

    out = tmp_path / "out"
    extra = ["--pairs", "2"] if command == "eval" else []
    code = main([command, "--data", str(tmp_path / "no-data"), *extra, "--executor", "ray",
                 "--out", str(out), *args])
    err = capsys.readouterr().err
    assert not out.exists()  # nothing half-written
    assert list(tmp_path.iterdir()) == []
    return code, err.strip()


@pytest.fixture
def no_token(monkeypatch, tmp_path_factory):
    """No token anywhere Ray looks (an empty home for ~/.ray/auth_token)."""
    for name in ("RAY_AUTH_TOKEN", "RAY_AUTH_TOKEN_PATH", "RAY_AUTH_MODE", "RAY_ADDRESS"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("HOME", str(tmp_path_factory.mktemp("home")))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("text, form", [
    ("ray://head:10001", (True, "head", 10001)),
    ("head:6379", (False, "head", 6379)),
    ("ray://[::1]:10001", (True, "::1", 10001)),
])
def test_both_address_forms_parse(text, form):
    address = parse_address(text)
    assert (address.client, address.host, address.port) == form
    assert address.text == text


@pytest.mark.parametrize("command", ["eval", "robustness"])
@pytest.mark.parametrize("address", ["head", "http://head:8265", "ray://head", "head:0",
                                     "ray://head:70000"])
def test_a_malformed_address_names_both_forms(tmp_path, capsys, no_token, command, address):
    code, err = _run(tmp_path, capsys, "--address", address, command=command)
    assert code == 2 and len(err.splitlines()) == 1, err
    assert f"--address {address}:" in err and "ray://HOST:PORT" in err and "HOST:PORT" in err


@pytest.mark.parametrize("command", ["eval", "robustness"])
@pytest.mark.parametrize("scheme", ["", "ray://"])
def test_nothing_listening_is_one_line_naming_the_address(tmp_path, capsys, no_token, command,
                                                         scheme):
    address = f"{scheme}127.0.0.1:{_free_port()}"
    code, err = _run(tmp_path, capsys, "--address", address, command=command)
    assert code == 2 and len(err.splitlines()) == 1, err
    assert f"--address {address}:" in err and "connection refused" in err
    assert "ray start --head" in err


def test_an_unknown_host_is_one_line(tmp_path, capsys, no_token):
    code, err = _run(tmp_path, capsys, "--address", "ray://HEAD-NODE.invalid:10001")
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "cannot resolve the host 'HEAD-NODE.invalid'" in err


@pytest.fixture
def silent_server():
    """A TCP port that accepts connections and never answers (a head that failed to
    start behind a proxy, or a wrong service), on 127.0.0.1 and where Ray connects for
    it (the GCS form replaces the loopback by the node's address)."""
    resolved = ray_cluster.ray_target(parse_address("127.0.0.1:1"))
    server = socket.socket()
    server.bind((resolved.target or resolved.host, 0))
    server.listen(8)
    accepted = []

    def accept(listener):
        while True:
            try:
                accepted.append(listener.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, args=(server,), daemon=True).start()
    port = server.getsockname()[1]
    loopback = socket.socket()
    try:
        loopback.bind(("127.0.0.1", port))
        loopback.listen(8)
    except OSError:  # the node's address is the loopback itself
        loopback.close()
    threading.Thread(target=accept, args=(loopback,), daemon=True).start()
    try:
        yield port
    finally:
        loopback.close()
        server.close()
        for connection in accepted:
            connection.close()


@pytest.mark.parametrize("scheme, server", [("", "Ray GCS"), ("ray://", "Ray Client server")])
def test_a_port_that_never_answers_fails_within_the_limit(tmp_path, capsys, no_token,
                                                          monkeypatch, silent_server, scheme,
                                                          server):
    monkeypatch.setattr(ray_cluster, "LIMITS", ConnectLimits(reach_s=2.0, answer_s=6.0))
    address = f"{scheme}127.0.0.1:{silent_server}"
    code, err = _run(tmp_path, capsys, "--address", address)
    assert code == 2 and len(err.splitlines()) == 1, err
    # the probe process was killed at the limit: not Ray's minutes of retries
    assert f"--address {address}: no {server} answered at " in err
    assert err.endswith("(no answer within 6 s)"), err


def test_a_ray_client_address_without_ray_client_is_one_line(tmp_path, capsys, no_token,
                                                             monkeypatch):
    monkeypatch.setitem(sys.modules, "grpc", None)  # `import grpc` fails as if not installed
    code, err = _run(tmp_path, capsys, "--address", "ray://127.0.0.1:10001")
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "Ray Client, which is not installed: pip install -e '.[ray]'" in err
    assert "127.0.0.1:6379" in err  # the other form, which needs no Ray Client


def test_a_token_file_that_is_missing_or_empty_is_named(tmp_path_factory, tmp_path, capsys,
                                                        no_token, monkeypatch):
    empty = tmp_path_factory.mktemp("token") / "auth_token"
    empty.write_text("\n")
    for named in (empty, empty.with_name("missing")):
        monkeypatch.setenv("RAY_AUTH_TOKEN_PATH", str(named))
        code, err = _run(tmp_path, capsys, "--address", f"127.0.0.1:{_free_port()}")
        assert code == 2 and len(err.splitlines()) == 1, err
        assert f"RAY_AUTH_TOKEN_PATH={named}: no such file, or unreadable or empty" in err


def test_token_mode_without_a_token_says_where_to_put_it(tmp_path, capsys, no_token,
                                                         monkeypatch):
    monkeypatch.setenv("RAY_AUTH_MODE", "token")
    code, err = _run(tmp_path, capsys, "--address", f"127.0.0.1:{_free_port()}")
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "RAY_AUTH_MODE=token but no token was found" in err
    assert "ray get-auth-token" in err and "RAY_AUTH_TOKEN_PATH" in err


def test_the_token_is_found_where_ray_looks_and_never_shown(tmp_path, no_token, monkeypatch):
    secret = "0123456789abcdef-not-a-real-token"
    home_token = tmp_path / "home" / ".ray" / "auth_token"
    home_token.parent.mkdir(parents=True)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert ray_cluster.resolve_auth() == ray_cluster.Auth("disabled", None, False)
    home_token.write_text(secret + "\n")
    auth = ray_cluster.resolve_auth()
    assert auth == ray_cluster.Auth("token", "~/.ray/auth_token", True)
    named = tmp_path / "named"
    named.write_text(secret)
    monkeypatch.setenv("RAY_AUTH_TOKEN_PATH", str(named))
    assert ray_cluster.resolve_auth().source == f"RAY_AUTH_TOKEN_PATH ({named})"
    monkeypatch.setenv("RAY_AUTH_TOKEN", secret)
    assert ray_cluster.resolve_auth().source == "RAY_AUTH_TOKEN"
    monkeypatch.setenv("RAY_AUTH_MODE", "disabled")
    assert ray_cluster.resolve_auth() == ray_cluster.Auth("disabled", None, False)
    # token mode is switched on only while connected, and the environment restored
    monkeypatch.delenv("RAY_AUTH_MODE")
    with ray_cluster.auth_environment(ray_cluster.resolve_auth()):
        assert os.environ["RAY_AUTH_MODE"] == "token"
    assert "RAY_AUTH_MODE" not in os.environ
    for message in (ray_cluster.explain(parse_address("h:1"), auth, status, "detail")
                    for status in ("auth", "not_ray", "no_answer", "error")):
        assert secret not in message


class _FlakyRay:
    """A stand-in for ``ray`` whose ``init`` fails with the given errors first."""

    def __init__(self, *errors):
        self.errors, self.inits, self.shutdowns = list(errors), 0, 0

    def init(self, address, **options):
        self.inits += 1
        if self.errors:
            raise self.errors.pop(0)

    def shutdown(self):
        self.shutdowns += 1


@pytest.fixture
def checked_client_address(monkeypatch):
    """A Ray Client address whose check before ``ray.init`` passes without a cluster."""
    address = ray_cluster.ray_target(parse_address("ray://127.0.0.1:10001"))
    auth = ray_cluster.Auth("disabled", None, False)
    monkeypatch.setattr(ray_cluster, "check_cluster", lambda text, limits=None: (address, auth))
    return address.text


@pytest.mark.parametrize("message", [
    "Starting Ray client server failed. See ray_client_server_23000.err for detail logs.",
    "ConnectionError: ray client connection failed\npsutil.ZombieProcess: PID still exists "
    "but it's a zombie (pid=7733)",
])
def test_a_client_server_that_dies_while_starting_is_tried_again(checked_client_address,
                                                                 message):
    ray = _FlakyRay(ConnectionError(message))
    with ray_cluster.cluster_connection(ray, checked_client_address, {}):
        assert ray.inits == 2
    assert ray.shutdowns == 2  # after the failed try, and at the end


def test_another_connection_error_is_one_line_without_a_second_try(checked_client_address):
    ray = _FlakyRay(ConnectionError("version mismatch: the cluster runs Ray 2.9"))
    with pytest.raises(UsageError, match="ray://127.0.0.1:10001.*version mismatch"):
        with ray_cluster.cluster_connection(ray, checked_client_address, {}):
            pass
    assert ray.inits == 1
