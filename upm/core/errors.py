"""The project's error types.

Every error a user can cause by giving bad input (a malformed file, a wrong argument)
is an :class:`UpmError`. The command line prints its message on one line and exits 2.
"""

from __future__ import annotations

import os


class UpmError(Exception):
    """Base class of every error caused by bad input."""


class DataFileError(UpmError):
    """A malformed or inconsistent data file (ASF, AMC, CSV, saved map).

    Parameters
    ----------
    path : str or os.PathLike
        The file at fault.
    message : str
        What is wrong, in words a user can act on.
    line : int, optional
        1-based line number at fault, when one line is.
    """

    def __init__(self, path: str | os.PathLike, message: str, line: int | None = None):
        self.path = os.fspath(path)
        self.line = line
        self.reason = message
        where = self.path if line is None else f"{self.path}:{line}"
        super().__init__(f"{where}: {message}")


class UsageError(UpmError):
    """A bad argument or combination of arguments."""
