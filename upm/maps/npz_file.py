"""Reading a posture-map file (``.npz``) safely: member by member with
``allow_pickle=False``, its size and compression bounded before anything is decompressed
(a zip bomb is refused unread), its format and version checked. Every failure is a
:class:`~upm.core.errors.DataFileError` naming the file."""

from __future__ import annotations

import tokenize
import zipfile
import zlib

import numpy as np

from upm.core.errors import DataFileError
from upm.motion.skeleton import CLASS_NAMES

FILE_FORMAT = "upm-controller/posture-map"
FORMAT_VERSION = 1

#: Bounds on a map archive, checked from the zip directory before anything is
#: decompressed (a zip bomb is refused unread). A 2,000-neuron map is under 2 MB.
MAX_MEMBERS = 64
MAX_UNCOMPRESSED_BYTES = 1 << 30
MAX_COMPRESSION_RATIO = 200
#: What reading a damaged archive member can raise (zip, zlib, the .npy header).
_ARCHIVE_ERRORS = (OSError, ValueError, EOFError, KeyError, TypeError, SyntaxError,
                   RuntimeError, NotImplementedError, OverflowError, zipfile.BadZipFile,
                   zlib.error, tokenize.TokenError)


def read_map_arrays(path) -> dict:
    """Every array of a posture-map file, checked for format and version.

    The archive is read member by member with ``allow_pickle=False`` (an object array
    is refused, never unpickled), after its directory is checked against
    :data:`MAX_MEMBERS`, :data:`MAX_UNCOMPRESSED_BYTES` and
    :data:`MAX_COMPRESSION_RATIO`.
    """
    try:
        with open(path, "rb") as handle:
            magic = handle.read(4)
    except FileNotFoundError:
        raise DataFileError(path, "no such file") from None
    except OSError as exc:
        raise DataFileError(path, f"cannot read: {exc.strerror}") from None
    if magic != b"PK\x03\x04":  # every .npz is a zip archive
        raise DataFileError(path, "not a posture map: not an .npz (zip) archive "
                                  "(write one with 'upm train --out MAP.npz')")
    try:
        with zipfile.ZipFile(path) as archive:
            members = archive.infolist()
            _check_members(path, members)
            arrays = {}
            for info in members:
                with archive.open(info) as member:
                    arrays[info.filename[:-len(".npy")]] = np.lib.format.read_array(
                        member, allow_pickle=False)
    except DataFileError:
        raise
    except _ARCHIVE_ERRORS as exc:
        reason = " ".join(str(exc).split())[:200] or type(exc).__name__
        if "allow_pickle" in reason:
            reason = "it holds a Python object array, which is never unpickled"
        raise DataFileError(path, f"not a readable posture map (.npz): {reason}") from None
    if "format" not in arrays:
        raise DataFileError(path, "not a posture map file (no 'format' field)")
    if text_field(arrays, "format", path) != FILE_FORMAT:
        raise DataFileError(path, f"not a posture map file (format "
                                  f"{text_field(arrays, 'format', path)!r})")
    version = arrays.get("format_version")
    if version is None or version.shape != () or version.dtype.kind not in "iu":
        raise DataFileError(path, "no valid format_version")
    if int(version) != FORMAT_VERSION:
        raise DataFileError(path, f"format version {int(version)} is not supported (this "
                                  f"program reads version {FORMAT_VERSION}); train the map again")
    for key in ("kind", "class_names", "class_slices", "dof_names", "meta_json"):
        if key not in arrays:
            raise DataFileError(path, f"missing field {key}")
    return arrays


def _check_members(path, members) -> None:
    if len(members) > MAX_MEMBERS:
        raise DataFileError(path, f"not a posture map: {len(members)} archive members "
                                  f"(at most {MAX_MEMBERS})")
    total = 0
    for info in members:
        if not info.filename.endswith(".npy") or info.filename.count("/"):
            raise DataFileError(path, f"not a posture map: archive member {info.filename!r} "
                                      "is not an .npy array")
        total += info.file_size
        ratio = info.file_size / max(info.compress_size, 1)
        if total > MAX_UNCOMPRESSED_BYTES or ratio > MAX_COMPRESSION_RATIO:
            raise DataFileError(path, f"archive member {info.filename!r} would decompress to "
                                      f"{info.file_size} bytes (ratio {ratio:.0f}): refused "
                                      "unread as a possible zip bomb")


def text_list(arrays: dict, key: str, path) -> tuple[str, ...]:
    value = arrays[key]
    if value.ndim != 1 or value.dtype.kind != "U":
        raise DataFileError(path, f"field {key} must be a list of names, not {value.dtype} "
                                  f"{value.shape}")
    return tuple(str(x) for x in value)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value)


def check_meta(stats: dict, provenance: dict, path) -> None:
    """Refuse metadata the summaries (``upm train``, ``upm map-info``) cannot print."""
    def bad(what: str):
        return DataFileError(path, f"corrupt metadata (meta_json): {what}")

    if set(stats) != set(CLASS_NAMES):
        raise bad(f"stats must cover the classes {', '.join(CLASS_NAMES)}")
    for c, s in stats.items():
        if not isinstance(s, dict):
            raise bad(f"stats of {c} is not a record")
        for key in ("neurons", "quantisation_error_mean_deg", "quantisation_error_max_deg"):
            if not _is_number(s.get(key)):
                raise bad(f"stats of {c} lacks a number {key}")
        if s.get("radius_deg") is not None and not _is_number(s["radius_deg"]):
            raise bad(f"stats of {c}: radius_deg is not a number")
        grid = s.get("grid")
        if grid is not None and not (isinstance(grid, list) and len(grid) == 2
                                     and all(isinstance(v, int) for v in grid)):
            raise bad(f"stats of {c}: grid is not [rows, cols]")
    names = provenance.get("clip_names", [])
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise bad("provenance clip_names is not a list of names")
    for key in ("n_samples", "train_seconds"):
        if provenance.get(key) is not None and not _is_number(provenance[key]):
            raise bad(f"provenance {key} is not a number")


def text_field(arrays: dict, key: str, path) -> str:
    value = arrays.get(key)
    if value is None or value.shape != () or value.dtype.kind != "U":
        raise DataFileError(path, f"field {key} must be a text value")
    return str(value)
