"""The study on a Ray cluster started on its own, as a user with a cluster runs it.

The head is started here with ``ray start --head``: token authentication on (a token of
its own in a temporary file), 2 CPUs, its own temporary directory and ports, everything on
127.0.0.1; it is stopped by its own process group when the module ends, however it ends.
The drivers are ``upm eval`` processes that get the token the way a user has it (the file
in RAY_AUTH_TOKEN_PATH, RAY_AUTH_MODE unset). The README's command, through Ray Client, is
stopped by SIGTERM once a free-root run is in the checkpoint, then completed through the
head's GCS address; the outputs equal the local pool's byte for byte and hold no token. A
missing or wrong token is one line naming the fix. (One test for the one head: pytest-xdist
would start a head for each worker that runs a test of the module.)
"""

from __future__ import annotations

import contextlib
import os
import random
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

pytest.importorskip("ray")
pytest.importorskip("grpc")  # ray[client]

pytestmark = pytest.mark.physics

#: The smallest real study with the free-root test: 2 pairs, 1 of them simulated, two
#: methods (3 free-root runs: 1 pair x 2 methods + 1 real window), by the real-time
#: controller (the executors are compared, not the efforts).
STUDY = ["--pairs", "2", "--windows", "20", "--methods", "upm", "linear", "--no-figures",
         "--physics", "--physics-pairs", "1", "--effort", "realtime"]
#: The outputs that are the same bytes whatever runs them (eval.outputs).
DETERMINISTIC = ("scores.csv", "results.json", "summary.csv", "paired.csv", "summary.md",
                 "physics.csv")
#: Ray's switch for a one-machine cluster: the node's address is 127.0.0.1 and the GCS
#: listens there only (else Ray takes the machine's own address and every interface).
LOOPBACK = {"RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
#: Generous: a loaded 2-core machine.
START_S = 120.0
STUDY_S = 900.0


@dataclass(frozen=True)
class Head:
    """A head started by this module.

    Attributes
    ----------
    gcs : str
        ``127.0.0.1:PORT``: the GCS address.
    client : str
        ``ray://127.0.0.1:PORT``: the Ray Client address.
    token : str
        The cluster's token (only to check that no output holds it).
    env : dict
        A driver's environment: the token's file in RAY_AUTH_TOKEN_PATH, RAY_AUTH_MODE
        unset.
    """

    gcs: str
    client: str
    token: str
    env: dict


def _free_ports(n: int) -> list[int]:
    sockets = [socket.socket() for _ in range(n)]
    try:
        for s in sockets:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


def _free_window(n: int = 64) -> tuple[int, int]:
    """``n`` consecutive free ports for Ray's worker processes, below the ephemeral range
    and away from Ray's defaults (10002-19999) and Ray Client's servers (23000-24000)."""
    rng = random.Random()
    for _ in range(200):
        low = rng.randrange(24100, 32600 - n)
        try:
            for port in range(low, low + n):
                with socket.socket() as s:
                    s.bind(("127.0.0.1", port))
        except OSError:
            continue
        return low, low + n - 1
    pytest.skip("no window of free ports for Ray's workers")


def _ray_command() -> list[str]:
    script = Path(sys.executable).with_name("ray")
    if script.is_file():
        return [str(script)]
    return [sys.executable, "-c", "import sys; from ray.scripts.scripts import main; "
            "sys.argv[0] = 'ray'; main()"]


def _driver_env() -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("RAY_AUTH_MODE", "RAY_AUTH_TOKEN", "RAY_AUTH_TOKEN_PATH", "RAY_ADDRESS")}
    return {**env, **LOOPBACK}


def _listening(port: int) -> bool:
    with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 1.0):
        return True
    return False


def _stop_group(process: subprocess.Popen) -> None:
    """Stop what this module started: ``ray start --block`` stops its node on SIGTERM;
    anything of its process group still there after that is killed."""
    with contextlib.suppress(ProcessLookupError):
        process.send_signal(signal.SIGTERM)
    try:
        process.wait(timeout=60)
    except subprocess.TimeoutExpired:
        pass
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(process.pid, signal.SIGKILL)
    process.wait()


@pytest.fixture(scope="module")
def ray_head():
    # A short directory: Ray's socket paths under it must fit in 107 bytes.
    root = Path(tempfile.mkdtemp(prefix="upm-ray-"))
    token = secrets.token_hex(32)
    token_file = root / "auth_token"
    token_file.write_text(token)
    token_file.chmod(0o600)
    gcs, client, *ports = _free_ports(8)
    low, high = _free_window()
    env = {**_driver_env(), "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN_PATH": str(token_file)}
    command = [*_ray_command(), "start", "--head", "--block", "--node-ip-address", "127.0.0.1",
               "--port", str(gcs), "--ray-client-server-port", str(client),
               "--node-manager-port", str(ports[0]), "--object-manager-port", str(ports[1]),
               "--dashboard-agent-listen-port", str(ports[2]),
               "--dashboard-agent-grpc-port", str(ports[3]),
               "--metrics-export-port", str(ports[4]), "--runtime-env-agent-port",
               str(ports[5]), "--min-worker-port", str(low), "--max-worker-port", str(high),
               "--num-cpus", "2", "--include-dashboard", "false", "--disable-usage-stats",
               "--temp-dir", str(root / "ray")]
    log = open(root / "head.log", "w")  # noqa: SIM115 - closed in the finally
    process = subprocess.Popen(command, env=env, stdout=log, stderr=subprocess.STDOUT,
                               stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + START_S
        while not ("Ray runtime started" in (root / "head.log").read_text()
                   and _listening(gcs) and _listening(client)):
            if process.poll() is not None or time.monotonic() > deadline:
                pytest.fail("the head did not start:\n" + (root / "head.log").read_text()[-3000:])
            time.sleep(0.5)
        yield Head(gcs=f"127.0.0.1:{gcs}", client=f"ray://127.0.0.1:{client}", token=token,
                   env={**_driver_env(), "RAY_AUTH_TOKEN_PATH": str(token_file)})
    finally:
        _stop_group(process)
        log.close()
        shutil.rmtree(root, ignore_errors=True)


def _upm(*args, env, timeout=STUDY_S) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "upm", *args], env=env, capture_output=True,
                          text=True, timeout=timeout, stdin=subprocess.DEVNULL)


def _token_error(head: Head, tmp_path: Path, form: str, token: str) -> None:
    """A driver with the token missing or wrong: one line naming the address and the fix,
    exit 2, nothing written, no token shown."""
    tmp_path.mkdir()
    env = dict(head.env)
    if token == "missing":
        del env["RAY_AUTH_TOKEN_PATH"]
        env["HOME"] = str(tmp_path / "home")  # no ~/.ray/auth_token either
    else:
        (tmp_path / "other").write_text(secrets.token_hex(32))
        env["RAY_AUTH_TOKEN_PATH"] = str(tmp_path / "other")
    address = head.client if form == "client" else head.gcs
    out = tmp_path / "out"
    done = _upm("eval", *STUDY, "--executor", "ray", "--address", address, "--out", str(out),
                env=env, timeout=120)
    err = done.stderr.strip()
    assert done.returncode == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"upm eval: error: --address {address}: ")
    expected = ("asks for Ray's authentication token and none was found" if token == "missing"
                else "the cluster refused the authentication token from RAY_AUTH_TOKEN_PATH")
    assert expected in err and "ray get-auth-token" in err
    assert not out.exists()
    assert head.token not in done.stdout + done.stderr


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines() if path.is_file() else []


def test_the_readme_command_on_a_cluster_started_on_its_own(ray_head, data_dir, tmp_path):
    # Without the token, or with another one: refused, one line each.
    _token_error(ray_head, tmp_path / "missing", "client", "missing")
    _token_error(ray_head, tmp_path / "wrong", "gcs", "wrong")

    study = ["eval", "--data", str(data_dir), *STUDY]
    local, cluster = tmp_path / "local", tmp_path / "cluster"
    done = _upm(*study, "--workers", "2", "--out", str(local), env=ray_head.env)
    assert done.returncode == 0, done.stderr[-3000:]

    # The README's command (Ray Client), stopped by SIGTERM once a free-root run is kept.
    checkpoint = cluster / "physics-partial.jsonl"
    with open(tmp_path / "stopped.out", "w") as stdout, \
            open(tmp_path / "stopped.err", "w") as stderr:
        process = subprocess.Popen(
            [sys.executable, "-m", "upm", *study, "--executor", "ray", "--address",
             ray_head.client, "--out", str(cluster)], env=ray_head.env, stdout=stdout,
            stderr=stderr, stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            deadline = time.monotonic() + STUDY_S
            while len(_lines(checkpoint)) < 2 and process.poll() is None:
                assert time.monotonic() < deadline, "no free-root run finished"
                time.sleep(0.05)
            assert process.poll() is None, (tmp_path / "stopped.err").read_text()[-3000:]
            process.send_signal(signal.SIGTERM)
            code = process.wait(timeout=120)
        finally:
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
    stopped_err = (tmp_path / "stopped.err").read_text()
    assert code == 130, stopped_err[-3000:]
    assert stopped_err.strip().splitlines()[-1] == "upm eval: interrupted"
    with pytest.raises(ProcessLookupError):  # nothing of the stopped driver is left running
        os.killpg(process.pid, 0)
    assert sorted(p.name for p in cluster.iterdir()) == [checkpoint.name]  # nothing else
    kept = len(_lines(checkpoint)) - 1
    assert 1 <= kept < 3

    # The same command through the head's GCS address: only the missing runs, then the
    # outputs, the same bytes as the local pool's.
    done = _upm(*study, "--executor", "ray", "--address", ray_head.gcs, "--out", str(cluster),
                env=ray_head.env)
    assert done.returncode == 0, done.stderr[-3000:]
    assert f", {kept} runs resumed):" in done.stdout
    assert not checkpoint.exists()
    for name in DETERMINISTIC:
        assert (cluster / name).read_bytes() == (local / name).read_bytes(), name
    texts = [done.stdout, done.stderr, stopped_err, (tmp_path / "stopped.out").read_text()]
    texts += [p.read_text() for p in cluster.iterdir()]
    assert not any(ray_head.token in text for text in texts)
