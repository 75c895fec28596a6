"""Performance benchmarks (``upm bench``): every figure next to a reference measured in the
same run, and quoted as a ratio, since machines are noisy.

Each module of this package (discovered automatically) defines

- ``NAME``: a short name (the key in the JSON output), and
- ``run(context: BenchContext) -> dict``: JSON-serialisable figures. Each figure is
  timed with :func:`timeit_interleaved` against its reference (rounds of the figure and
  its reference alternate, so that both see the same machine load), and reported as
  medians with the median of the per-round ratios.
"""

from __future__ import annotations

import importlib
import pkgutil
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class BenchContext:
    """What every benchmark may use.

    Attributes
    ----------
    data_dir : Path
        The CMU clips.
    quick : bool
        Fewer repetitions and smaller inputs (used by the test suite).
    soak_s : float or None
        Simulated seconds of the soak (``upm bench --soak-s``; None: its default, an
        hour, or a few seconds with ``quick``).
    """

    data_dir: Path
    quick: bool = False
    soak_s: float | None = None


def timeit_best(fn: Callable[[], object], repeat: int = 5, number: int = 1) -> float:
    """Best wall-clock seconds per call of ``fn`` over ``repeat`` rounds of ``number`` calls."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - start) / number)
    return best


def timeit_interleaved(fn: Callable[[], object], reference: Callable[[], object],
                       rounds: int = 7, number: int = 1,
                       warmup: bool = True) -> dict[str, float]:
    """Time ``fn`` and its ``reference`` in alternating rounds; medians.

    Each round times ``number`` calls of ``fn`` then ``number`` calls of ``reference``
    (the order flips every round), so a change of machine load hits both alike. With
    ``warmup`` each runs once untimed first.

    Returns
    -------
    dict
        ``s`` and ``reference_s``: median seconds per call; ``ratio``: median over rounds
        of the per-round ratio ``fn / reference``; ``ratio_min``, ``ratio_max``: its range
        (how noisy the machine was); ``rounds``.
    """
    def once(f):
        start = time.perf_counter()
        for _ in range(number):
            f()
        return (time.perf_counter() - start) / number

    if warmup:  # caches and lazy builds outside the timing
        fn()
        reference()
    own, ref = [], []
    for i in range(rounds):
        if i % 2:
            ref.append(once(reference))
            own.append(once(fn))
        else:
            own.append(once(fn))
            ref.append(once(reference))
    ratios = [a / b for a, b in zip(own, ref, strict=True)]
    return {"s": statistics.median(own), "reference_s": statistics.median(ref),
            "ratio": statistics.median(ratios), "ratio_min": min(ratios),
            "ratio_max": max(ratios), "rounds": rounds}


def target(value: float, limit: float, ratio: float | None = None,
           ratio_limit: float | None = None) -> dict:
    """A speed target of issue 13 beside the figure: the absolute ``limit`` (met or not on
    this machine, as loaded as it is) and, where the figure has a same-run reference,
    the ratio that ``limit`` was against that reference when the target was set (the
    figure that carries across machines and load).

    Returns
    -------
    dict
        ``value``, ``target``, ``met``; with a ratio also ``ratio``, ``target_ratio``,
        ``met_by_ratio``.
    """
    out = {"value": value, "target": limit, "met": bool(value <= limit)}
    if ratio is not None and ratio_limit is not None:
        out.update(ratio=ratio, target_ratio=ratio_limit, met_by_ratio=bool(ratio <= ratio_limit))
    return out


def ratio_target(ratio: float, limit: float, reference: str, **context) -> dict:
    """A speed target set as a ratio to a reference measured in the same run (the figure
    that carries across machines and load), judged on that ratio alone.

    Parameters
    ----------
    ratio : float
        The figure over its same-run reference.
    limit : float
        The largest ratio that meets the target.
    reference : str
        What the ratio is against.
    **context
        Figures shown beside it (e.g. the absolute time, the absolute target the ratio
        came from); not judged.

    Returns
    -------
    dict
        ``value`` (the ratio), ``target`` (``limit``), ``met`` (``value <= target``),
        ``unit`` ("ratio"), ``reference``, then ``context``.
    """
    return {"value": ratio, "target": limit, "met": bool(ratio <= limit), "unit": "ratio",
            "reference": reference, **context}


def missed_targets(report: dict) -> list[str]:
    """One line per target missed in a ``upm bench`` report: every entry of each
    benchmark's ``targets`` whose ``met`` (or, where it has one, ``met_by_ratio``) is false.
    """
    lines = []
    for bench, figures in report.get("benchmarks", {}).items():
        for name, entry in figures.get("targets", {}).items():
            missed = []
            if not entry["met"]:
                unit = "x the reference" if entry.get("unit") == "ratio" else ""
                missed.append(f"{entry['value']:.4g}{unit} > target {entry['target']:.4g}{unit}")
            if entry.get("met_by_ratio") is False:
                missed.append(f"ratio to the reference {entry['ratio']:.3g} > target "
                              f"{entry['target_ratio']:.3g}")
            if missed:
                lines.append(f"upm bench: target missed: {bench}.{name}: {'; '.join(missed)}")
    return lines


def clip_on_humanoid(context: BenchContext, clip: str, quick_frames: int):
    """A real clip (its first ``quick_frames`` frames in quick mode) and the humanoid of its
    subject: the material of the MuJoCo benchmarks.

    Returns
    -------
    motion : upm.Motion
    model : mujoco.MjModel
    """
    from humanoid_xml import catalog_model_path, load_model
    from upm.motion.catalog import Catalog

    catalog = Catalog(context.data_dir)
    clip = clip if clip in catalog else catalog.names()[0]
    motion = catalog.load(clip)
    if context.quick:
        motion = motion.frames(0, quick_frames)
    return motion, load_model(catalog_model_path(catalog, clip))


def discover() -> dict[str, object]:
    """The benchmark modules of this package, by ``NAME``, in module-name order."""
    found = {}
    for info in sorted(pkgutil.iter_modules([str(Path(__file__).parent)]), key=lambda i: i.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        found[module.NAME] = module
    return found
