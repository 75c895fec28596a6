"""The clip catalogue: CMU clips under a data directory, with their ASF and frame rate.

The clips of a data directory are its ``NN/NN_MM.amc`` files, each read with its
subject's ``NN/NN.asf``. A ``clips.csv`` beside them, where present, adds each clip's
frame rate, description and train/test split. A clip without a frame rate (missing
from ``clips.csv``, or no ``clips.csv`` at all) is read at 120 fps with a one-line
warning: never silently.
"""

from __future__ import annotations

import csv
import functools
import io
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

from upm.core.errors import DataFileError, UsageError
from upm.motion.amc import read_amc
from upm.motion.asf import read_asf
from upm.motion.motion import Motion
from upm.motion.skeleton import Skeleton

DEFAULT_FPS = 120.0
#: Highest frame rate clips.csv may give (motion capture runs at up to a few kHz).
MAX_FPS = 10000.0
#: Largest clips.csv read (the CMU list of 2,600 clips is about 200 kB).
MAX_MANIFEST_BYTES = 16 * 1024 * 1024
_CLIP_FILE = re.compile(r"^(\d+)_(\d+)\.amc$", re.IGNORECASE)
_CLIP_REF = re.compile(r"^(?P<name>[^@\s]+)(?:@(?P<start>-?\d*)(?::(?P<stop>-?\d*))?)?$")


def default_data_dir() -> Path:
    """The data directory: ``$UPM_DATA``, else ``shared/data/cmu`` beside the checkout.

    Raises
    ------
    UsageError
        If neither exists.
    """
    env = os.environ.get("UPM_DATA")
    if env:
        return Path(env)
    checkout = Path(__file__).resolve().parents[2]  # upm/motion/catalog.py -> the checkout
    beside = checkout.parent / "shared" / "data" / "cmu"
    if beside.is_dir():
        return beside
    raise UsageError("no data directory: pass --data DIR or set UPM_DATA to the CMU clips "
                     "(e.g. ../shared/data/cmu)")


@dataclass(frozen=True)
class ClipInfo:
    """One clip of the catalogue.

    Attributes
    ----------
    name : str
        e.g. ``"02_01"``.
    subject : str
        e.g. ``"02"``.
    amc_path, asf_path : Path
    fps : float
    split : str
        ``"train"``, ``"test"`` or ``""`` when not listed.
    description : str
    listed_frames : int or None
        The frame count ``clips.csv`` gives, if any.
    """

    name: str
    subject: str
    amc_path: Path
    asf_path: Path
    fps: float
    split: str
    description: str
    listed_frames: int | None


@dataclass(frozen=True)
class ClipRef:
    """A clip named on the command line: ``CLIP``, ``CLIP@FRAME`` or ``CLIP@A:B``.

    Frame numbers are 0-based; ``A:B`` is half-open like a Python slice (either end may
    be omitted; negative values count from the end).
    """

    name: str
    start: int | None = None
    stop: int | None = None
    has_range: bool = False

    def __str__(self) -> str:
        if self.has_range:
            a = "" if self.start is None else self.start
            b = "" if self.stop is None else self.stop
            return f"{self.name}@{a}:{b}"
        return self.name if self.start is None else f"{self.name}@{self.start}"


def parse_clip_ref(text: str) -> ClipRef:
    """Parse ``CLIP``, ``CLIP@FRAME`` or ``CLIP@A:B`` (UsageError if malformed)."""
    match = _CLIP_REF.match(text.strip())
    if not match or (match["start"] == "" and match["stop"] is None):
        raise UsageError(f"bad clip reference {text!r}: expected CLIP, CLIP@FRAME or CLIP@A:B")
    start = int(match["start"]) if match["start"] else None
    stop = int(match["stop"]) if match["stop"] else None
    return ClipRef(match["name"], start, stop, has_range=match["stop"] is not None)


class Catalog:
    """The clips of a data directory.

    Parameters
    ----------
    data_dir : path-like, optional
        Default: :func:`default_data_dir`.

    Raises
    ------
    UsageError
        If the directory does not exist or holds no clips.
    DataFileError
        If ``clips.csv`` is malformed.
    """

    def __init__(self, data_dir: str | os.PathLike | None = None):
        self.root = Path(data_dir) if data_dir is not None else default_data_dir()
        if not self.root.is_dir():
            raise UsageError(f"data directory {self.root} does not exist")
        listed = self._read_manifest(self.root / "clips.csv")
        clips: dict[str, ClipInfo] = {}
        unlisted: list[str] = []
        for amc in sorted(self.root.glob("*/*.amc")):
            match = _CLIP_FILE.match(amc.name)
            if not match:
                continue
            subject, name = match[1], amc.stem
            row = listed.get(name)
            if row is None and listed:
                warnings.warn(f"{name} is not in clips.csv: read at {DEFAULT_FPS:g} fps",
                              stacklevel=2)
            elif row is None:
                unlisted.append(name)
            clips[name] = ClipInfo(
                name=name,
                subject=subject,
                amc_path=amc,
                asf_path=amc.parent / f"{subject}.asf",
                fps=row["fps"] if row else DEFAULT_FPS,
                split=row["split"] if row else "",
                description=row["description"] if row else "",
                listed_frames=row["frames"] if row else None,
            )
        if not clips:
            raise UsageError(f"no clips (NN/NN_MM.amc files) under {self.root}")
        if unlisted:
            warnings.warn(f"no clips.csv in {self.root}: its {len(unlisted)} clips are read at "
                          f"{DEFAULT_FPS:g} fps (an AMC file carries no frame rate)",
                          stacklevel=2)
        self._clips = dict(sorted(clips.items(), key=lambda kv: _clip_sort_key(kv[0])))

    @staticmethod
    def _read_manifest(path: Path) -> dict[str, dict]:
        if not path.exists():
            return {}
        try:
            data = path.read_bytes()
        except OSError as exc:
            raise DataFileError(path, f"cannot read clips.csv: {exc.strerror or exc}") from None
        if len(data) > MAX_MANIFEST_BYTES:
            raise DataFileError(path, f"clips.csv is larger than {MAX_MANIFEST_BYTES} bytes")
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            line = data[:exc.start].count(b"\n") + 1
            raise DataFileError(path, "clips.csv is not UTF-8 text", line) from None
        if "\x00" in text:
            raise DataFileError(path, "binary data, not a text clips.csv")
        reader = csv.DictReader(io.StringIO(text, newline=""))
        try:
            return _manifest_rows(path, reader)
        except csv.Error as exc:
            raise DataFileError(path, f"malformed CSV: {exc}", reader.line_num or None) from None

    def __iter__(self):
        return iter(self._clips.values())

    def __len__(self) -> int:
        return len(self._clips)

    def __contains__(self, name: str) -> bool:
        return name in self._clips

    def names(self, split: str | None = None) -> list[str]:
        """Clip names, optionally only those of one split (``"train"``/``"test"``)."""
        return [c.name for c in self if split is None or c.split == split]

    def info(self, name: str) -> ClipInfo:
        """The clip called ``name`` (UsageError listing what exists if unknown)."""
        try:
            return self._clips[name]
        except KeyError:
            known = ", ".join(list(self._clips)[:8])
            raise UsageError(f"no clip {name!r} under {self.root} (clips: {known}, ...)") from None

    def skeleton(self, subject: str) -> Skeleton:
        """The ASF skeleton of a subject (read once, then cached)."""
        return _read_asf_cached(str(self.root / subject / f"{subject}.asf"))

    def load(self, name: str) -> Motion:
        """Read clip ``name`` at its catalogue frame rate."""
        info = self.info(name)
        return read_amc(info.amc_path, self.skeleton(info.subject), fps=info.fps, name=name)

    def load_ref(self, ref: ClipRef | str) -> Motion:
        """Read the frames a :class:`ClipRef` names (``CLIP@A:B``; ``CLIP@F`` is one frame)."""
        return self.load_span(ref)[0]

    def load_span(self, ref: ClipRef | str) -> tuple[Motion, int]:
        """The frames a :class:`ClipRef` names and the clip frame they start at (0-based)."""
        if isinstance(ref, str):
            ref = parse_clip_ref(ref)
        motion = self.load(ref.name)
        if not ref.has_range and ref.start is None:
            return motion, 0
        n = motion.n_frames
        start = ref.start if ref.start is not None else 0
        start = start + n if start < 0 else start
        stop = ref.stop if ref.has_range else start + 1
        if stop is None:
            stop = n
        stop = stop + n if stop < 0 else stop
        if ref.has_range and 0 <= start < n and 0 <= stop <= n and start >= stop:
            raise UsageError(f"{ref}: empty range (frame {start} is not before frame {stop}; "
                             "CLIP@A:B is frames A to B-1, so A must come before B)")
        if not 0 <= start < stop <= n:
            raise UsageError(f"{ref}: frames out of range (clip {ref.name} has {n} frames, "
                             f"numbered 0 to {n - 1})")
        return motion.frames(start, stop), start


def _manifest_rows(path: Path, reader: csv.DictReader) -> dict[str, dict]:
    need = {"clip", "fps"}
    if not reader.fieldnames or not need <= set(reader.fieldnames):
        raise DataFileError(path, "clips.csv needs at least the columns clip, fps", 1)
    rows = {}
    for row in reader:
        lineno = reader.line_num
        clip = (row.get("clip") or "").strip()
        if not clip:
            raise DataFileError(path, "a row without a clip name", lineno)
        if row.get("fps") is None or None in row:
            raise DataFileError(path, f"the row of {clip} does not have the header's "
                                      f"{len(reader.fieldnames)} columns", lineno)
        try:
            fps = float(row["fps"])
            frames = int(row["frames"]) if (row.get("frames") or "").strip() else None
        except ValueError:
            raise DataFileError(path, f"bad fps or frames for {clip}", lineno) from None
        if not 0 < fps <= MAX_FPS:
            raise DataFileError(path, f"fps {row['fps'].strip()} for {clip} is outside "
                                      f"(0, {MAX_FPS:g}]", lineno)
        if frames is not None and frames < 0:
            raise DataFileError(path, f"negative frame count for {clip}", lineno)
        rows[clip] = {
            "fps": fps,
            "frames": frames,
            "split": (row.get("split") or "").strip(),
            "description": (row.get("description") or "").strip(),
        }
    return rows


@functools.lru_cache(maxsize=64)
def _read_asf_cached(path: str) -> Skeleton:
    return read_asf(path)


def _clip_sort_key(name: str):
    subject, _, trial = name.partition("_")
    return (int(subject) if subject.isdigit() else subject, int(trial) if trial.isdigit() else 0)
