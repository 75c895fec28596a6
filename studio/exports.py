"""Where the studio's exports may go: one folder chosen at launch, and nowhere else.

The export field of the page is text anyone driving the page can set, so it names a file
*in* the export folder (``upm studio --out DIR``, default ``./studio-exports``, created on
the first export), never a path: a name with a path separator, ``..``, an absolute path,
a name that is a symlink leading out of the folder, or an extension other than ``.amc`` or
``.bvh`` is refused (:class:`ExportRefused`, whose message the page shows). An existing
file is never overwritten: the export takes the first free ``NAME-1.amc``,
``NAME-2.amc``... instead. The file is written to a temporary name in the folder, then
linked to its final name (which fails, rather than replaces, when that name appeared in
the meantime), so a reader never sees half a file.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

#: The extensions an export may have (the formats of :func:`upm.bvh.formats.write_motion`).
EXTENSIONS = (".amc", ".bvh")
#: Numbered names tried before giving up.
MAX_SUFFIX = 10_000


class ExportRefused(ValueError):
    """An export name the folder does not accept (the message says why)."""


def check_name(name: str) -> str:
    """``name`` if it is a plain ``.amc`` / ``.bvh`` file name, else :class:`ExportRefused`."""
    text = str(name)
    if not text.strip():
        raise ExportRefused("give a file name, e.g. transition.amc")
    if os.path.isabs(text) or text.startswith(("~", "\\")) or (len(text) > 1 and text[1] == ":"):
        raise ExportRefused(f"{text!r} is an absolute path: give a file name; exports go "
                            "into the studio's export folder (upm studio --out)")
    if ".." in text:
        raise ExportRefused(f"{text!r} contains '..': give a plain file name")
    if "/" in text or "\\" in text or (os.altsep and os.altsep in text):
        raise ExportRefused(f"{text!r} contains a path separator: give a plain file name")
    if any(ord(c) < 32 for c in text):
        raise ExportRefused(f"{text!r} contains a control character")
    if Path(text).suffix.lower() not in EXTENSIONS or Path(text).stem in ("", "."):
        raise ExportRefused(f"{text!r}: exports are .amc or .bvh files")
    return text


class ExportFolder:
    """The export folder (``root``, made absolute; created on the first write)."""

    def __init__(self, root: str | os.PathLike = "studio-exports"):
        self.root = Path(os.path.abspath(os.fspath(root)))

    def _inside(self, path: Path) -> bool:
        real_root = os.path.realpath(self.root)
        return os.path.commonpath([real_root, os.path.realpath(path)]) == real_root

    def target(self, name: str) -> Path:
        """The path ``name`` stands for in the folder (not yet made unique).

        Raises
        ------
        ExportRefused
            See :func:`check_name`; also for a name that is a symlink leading out of the
            folder.
        """
        path = self.root / check_name(name)
        if path.is_symlink() and not self._inside(path):
            raise ExportRefused(f"{name!r} is a symlink leading out of the export folder")
        return path

    def write(self, name: str, writer) -> Path:
        """Write a new file for ``name``: ``writer(tmp_path)`` writes it (choosing the
        format by the suffix), then it takes ``name`` or, if taken, the first free
        numbered name. Returns the path written.

        Raises
        ------
        ExportRefused
            For a refused name (nothing is written).
        """
        path = self.target(name)
        self.root.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".export-", suffix=path.suffix, dir=self.root)
        os.close(fd)
        try:
            writer(tmp)
            for n in range(MAX_SUFFIX):
                final = path if n == 0 else path.with_name(f"{path.stem}-{n}{path.suffix}")
                if os.path.lexists(final):
                    continue
                try:
                    _publish(tmp, final)
                except FileExistsError:  # taken meanwhile: try the next number
                    continue
                return final
            raise ExportRefused(f"{name!r}: {MAX_SUFFIX} numbered names are taken")
        finally:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)


def _publish(tmp: str, final: Path) -> None:
    """Give the finished ``tmp`` the name ``final`` without replacing a file of that name
    (a hard link fails on an existing name; where links are not supported, a rename after
    the check)."""
    os.chmod(tmp, 0o666 & ~_umask())
    try:
        os.link(tmp, final)
    except FileExistsError:
        raise
    except OSError:  # no hard links on this file system
        if os.path.lexists(final):
            raise FileExistsError(final) from None
        os.replace(tmp, final)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
