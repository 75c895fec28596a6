"""Reading text data files: binary detection, decoding, line splitting."""

from __future__ import annotations

import os

from upm.core.errors import DataFileError


def _open_binary(path: str | os.PathLike, kind: str):
    """Open a file for binary reading; a missing, directory or unreadable path is a
    :class:`DataFileError` naming it."""
    try:
        return open(path, "rb")
    except FileNotFoundError:
        raise DataFileError(path, f"no such {kind} file") from None
    except IsADirectoryError:
        raise DataFileError(path, f"is a directory, not an {kind} file") from None
    except OSError as exc:
        raise DataFileError(path, f"cannot read {kind} file: {exc.strerror}") from None


def read_text_lines(path: str | os.PathLike, kind: str) -> list[str]:
    """Read a text file as a list of lines (CRLF or LF), with clear errors.

    Parameters
    ----------
    path : path-like
    kind : str
        What the file should be (e.g. ``"ASF"``), for messages.

    Raises
    ------
    DataFileError
        If the file is missing, unreadable, empty or binary.
    """
    with _open_binary(path, kind) as handle:
        data = handle.read()
    if not data.strip():
        raise DataFileError(path, f"empty {kind} file")
    if b"\x00" in data:
        raise DataFileError(path, f"binary data, not a text {kind} file")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        # Comments may carry Windows code-page characters; the data itself is ASCII.
        text = data.decode("latin-1")
    return text.splitlines()


def iter_text_lines(path: str | os.PathLike, kind: str, max_bytes: int | None = None,
                    progress_bytes: int = 64 * 1024 * 1024):
    """Yield ``(line number, line)`` of a text file without holding it in memory.

    Same checks as :func:`read_text_lines` (missing, unreadable, empty, binary: a NUL
    byte in the first 64 KiB; UTF-8 else Latin-1 per line), plus a size limit; a
    progress bar by bytes for files over ``progress_bytes``.

    Raises
    ------
    DataFileError
        As :func:`read_text_lines`, or if the file is larger than ``max_bytes``.
    """
    from upm.core.progress import progress

    with _open_binary(path, kind) as handle:
        size = os.fstat(handle.fileno()).st_size
        if max_bytes is not None and size > max_bytes:
            raise DataFileError(path, f"{kind} file of {size} bytes is over the limit of "
                                      f"{max_bytes} bytes")
        if b"\x00" in handle.read(1 << 16):
            raise DataFileError(path, f"binary data, not a text {kind} file")
        handle.seek(0)
        bar = progress(total=size, unit="B", unit_scale=True, desc=os.path.basename(path),
                       disable=None if size > progress_bytes else True)
        any_text = False
        done = 0
        with bar:
            for lineno, raw in enumerate(_split_lines(handle), start=1):
                if lineno % 65536 == 0:
                    bar.update(handle.tell() - done)
                    done = handle.tell()
                if not any_text and raw.strip():
                    any_text = True
                try:
                    yield lineno, raw.decode("utf-8")
                except UnicodeDecodeError:
                    yield lineno, raw.decode("latin-1")
            bar.update(size - done)
        if not any_text:
            raise DataFileError(path, f"empty {kind} file")


def _split_lines(handle):
    """Lines of a binary file ending in LF, CRLF or a lone CR."""
    for raw in handle:
        raw = raw[:-1] if raw.endswith(b"\n") else raw
        raw = raw[:-1] if raw.endswith(b"\r") else raw
        yield from raw.split(b"\r")
