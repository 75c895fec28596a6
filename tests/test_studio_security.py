"""What a web page may make the studio do, without the CMU data: the Origin rule of its
websocket (:mod:`studio.origin`) and the export folder (:mod:`studio.exports`). The
handshake itself, on a running studio, is tested in tests/test_studio.py."""

from __future__ import annotations

import os

import pytest

from studio.exports import ExportFolder, ExportRefused
from studio.origin import OriginGuard, is_loopback, normalise_origin, own_origins, parse_allowed
from upm.core.errors import UsageError


def test_own_origins_are_the_loopback_spellings_at_the_port():
    own = own_origins("127.0.0.1", 8080)
    assert own == {"http://localhost:8080", "http://127.0.0.1:8080", "http://[::1]:8080"}
    assert normalise_origin("HTTP://LocalHost:8080") in own
    assert normalise_origin("http://localhost:8081") not in own
    assert normalise_origin("https://localhost:8080") not in own
    assert normalise_origin("http://evil.example") not in own
    # a wildcard host adds no origin (the machine's names are given with --allow-origin)
    assert own_origins("0.0.0.0", 8080) == own
    assert "http://myhost:8080" in own_origins("myhost", 8080)
    assert "http://tools.example:9000" in own_origins("127.0.0.1", 8080,
                                                      parse_allowed(["http://tools.example:9000"]))


@pytest.mark.parametrize("bad", ["evil.example", "http://", "ftp://host", "http://h/path",
                                 "http://h:99999", "http://u@h"])
def test_a_bad_allowed_origin_is_a_usage_error(bad):
    with pytest.raises(UsageError, match="--allow-origin"):
        parse_allowed([bad])


def test_loopback_hosts():
    assert all(is_loopback(h) for h in ("127.0.0.1", "localhost", "::1", "[::1]", "127.0.0.2"))
    assert not any(is_loopback(h) for h in ("0.0.0.0", "::", "192.168.1.4", "myhost"))


class _Request:
    def __init__(self, **headers):
        self.headers = headers


class _Connection:
    local_address = ("127.0.0.1", 8080)

    def respond(self, status, text):
        return (int(status), text)


def test_guard_refuses_foreign_and_missing_origins_and_lets_the_page_in(caplog):
    guard = OriginGuard("127.0.0.1", parse_allowed(["http://tools.example:9000"]))
    conn = _Connection()
    for origin in ("http://localhost:8080", "http://127.0.0.1:8080", "http://[::1]:8080",
                   "http://tools.example:9000"):
        assert guard.check(conn, _Request(Upgrade="websocket", Origin=origin)) is None
    with caplog.at_level("WARNING", logger="studio.origin"):
        for headers in ({"Origin": "http://evil.example"}, {"Origin": "null"}, {},
                        {"Origin": "http://localhost:8081"}):
            status, _ = guard.check(conn, _Request(Upgrade="websocket", **headers))
            assert status == 403
    assert guard.refused == 4
    assert "http://evil.example" in caplog.text and "--allow-origin" in caplog.text
    # the page's own files are plain HTTP: served whatever the Origin
    assert guard.check(conn, _Request(Origin="http://evil.example")) is None


def _files(root) -> set[str]:
    return {os.path.relpath(os.path.join(d, f), root) for d, _, fs in os.walk(root) for f in fs}


def _writer(text="motion"):
    return lambda tmp: open(tmp, "w").write(text)


def test_export_refusals_write_nothing_anywhere(tmp_path):
    box = tmp_path / "work" / "exports"
    folder = ExportFolder(box)
    (tmp_path / "work").mkdir()
    victim = tmp_path / "victim.amc"
    victim.write_text("precious")
    box.mkdir()
    (box / "out.amc").symlink_to(victim)                  # an existing file outside
    (box / "dangling.bvh").symlink_to(tmp_path / "new.bvh")  # a file yet to be made outside
    before = _files(tmp_path)
    refused = {"../x.amc": "'..'", str(tmp_path / "abs.amc"): "absolute",
               "~/.bashrc": "absolute", "a/b.amc": "separator", "a\\b.amc": "separator",
               "x.txt": ".amc or .bvh", "x": ".amc or .bvh", ".amc": ".amc or .bvh",
               "": "file name", "out.amc": "symlink", "dangling.bvh": "symlink"}
    for name, why in refused.items():
        with pytest.raises(ExportRefused, match=why):
            folder.write(name, _writer())
    assert _files(tmp_path) == before
    assert victim.read_text() == "precious" and not (tmp_path / "new.bvh").exists()


def test_export_never_overwrites_and_leaves_no_temporary_file(tmp_path):
    folder = ExportFolder(tmp_path / "exports")  # made on the first export
    first = folder.write("take.amc", _writer("one"))
    second = folder.write("take.amc", _writer("two"))
    third = folder.write("take.amc", _writer("three"))
    assert [p.name for p in (first, second, third)] == ["take.amc", "take-1.amc", "take-2.amc"]
    assert [p.read_text() for p in (first, second, third)] == ["one", "two", "three"]
    assert _files(tmp_path / "exports") == {"take.amc", "take-1.amc", "take-2.amc"}
    # a failing writer leaves nothing behind
    with pytest.raises(OSError):
        folder.write("broken.bvh", lambda tmp: (_ for _ in ()).throw(OSError("disk full")))
    assert _files(tmp_path / "exports") == {"take.amc", "take-1.amc", "take-2.amc"}


def test_a_symlink_staying_inside_the_folder_gets_a_suffix(tmp_path):
    folder = ExportFolder(tmp_path)
    (tmp_path / "real.amc").write_text("kept")
    (tmp_path / "alias.amc").symlink_to(tmp_path / "real.amc")
    path = folder.write("alias.amc", _writer("new"))
    assert path.name == "alias-1.amc" and (tmp_path / "real.amc").read_text() == "kept"
