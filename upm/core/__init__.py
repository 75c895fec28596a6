"""The foundation every room of :mod:`upm` stands on: the project's errors, atomic file
writing, line-numbered text reading, the cache folder and progress bars."""

from upm.core.errors import DataFileError, UpmError, UsageError

__all__ = ["DataFileError", "UpmError", "UsageError"]
