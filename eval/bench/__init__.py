"""Performance benchmarks (``upm bench``): every figure next to a reference measured in the
same run, and quoted as a ratio, since machines are noisy.

Each module of this package (discovered automatically) defines

- ``NAME``: a short name (the key in the JSON output), and
- ``run(context: BenchContext) -> dict``: JSON-serialisable figures. Seconds are
  measured with :func:`timeit_best`; each reference figure sits beside the figure it
  calibrates, with the ratio.
"""

from __future__ import annotations

import importlib
import pkgutil
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
    """

    data_dir: Path
    quick: bool = False


def timeit_best(fn: Callable[[], object], repeat: int = 5, number: int = 1) -> float:
    """Best wall-clock seconds per call of ``fn`` over ``repeat`` rounds of ``number`` calls."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - start) / number)
    return best


def clip_on_humanoid(context: BenchContext, clip: str, quick_frames: int):
    """A real clip (its first ``quick_frames`` frames in quick mode) and the humanoid of its
    subject: the material of the MuJoCo benchmarks.

    Returns
    -------
    motion : upm.Motion
    model : mujoco.MjModel
    """
    from humanoid_xml import catalog_model_path, load_model
    from upm.catalog import Catalog

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
