"""Reading text data files: binary detection, decoding, line splitting."""

from __future__ import annotations

import os

from upm.errors import DataFileError


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
    try:
        with open(path, "rb") as handle:
            data = handle.read()
    except FileNotFoundError:
        raise DataFileError(path, f"no such {kind} file") from None
    except IsADirectoryError:
        raise DataFileError(path, f"is a directory, not an {kind} file") from None
    except OSError as exc:
        raise DataFileError(path, f"cannot read {kind} file: {exc.strerror}") from None
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
