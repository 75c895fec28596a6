"""Where the models live: the default (generic adult) model kept in the package, and
subject models built on demand from their ASF and cached outside the repository
(:func:`upm.core.cache.cache_dir`), keyed by the ASF's bytes and the generator's own source."""

from __future__ import annotations

import os
from pathlib import Path

from humanoid_xml.generator import GENERATOR_VERSION, build_mjcf
from upm.core.cache import cache_dir, digest
from upm.core.errors import DataFileError, UsageError

_PACKAGE = Path(__file__).resolve().parent
#: The source files whose content decides a generated model.
_GENERATOR_SOURCES = ("generator.py", "body.py", "exclusions.py", "frames.py", "servos.py",
                      "strength.py")


def default_model_path() -> Path:
    """The default model: the generic adult (``generic_adult.xml`` in this package)."""
    return _PACKAGE / "generic_adult.xml"


def generator_digest() -> str:
    """A digest of the generator version, its source files and the MuJoCo version (the
    actuator gains come from MuJoCo's mass matrix)."""
    import mujoco

    sources = [(_PACKAGE / name).read_bytes() for name in _GENERATOR_SOURCES]
    # the hinge ranges are the human range of motion's (upm.motion.human_boxes)
    motion = _PACKAGE.parent / "upm" / "motion"
    sources += [(motion / name).read_bytes()
                for name in ("anatomy.py", "human_rom.py", "human_boxes.py")]
    return digest(GENERATOR_VERSION, mujoco.__version__, *sources)


def subject_model_path(asf_path: str | os.PathLike) -> Path:
    """The model of the skeleton in ``asf_path``, built and cached on first use.

    Parameters
    ----------
    asf_path : path-like
        An ASF file (e.g. a CMU subject's ``NN/NN.asf``).

    Returns
    -------
    Path
        ``<cache>/models/humanoid-<stem>-<digest>.xml``, the digest covering the ASF's
        bytes and :func:`generator_digest`, so a changed ASF or generator never reuses a
        stale model.

    Raises
    ------
    DataFileError
        If the ASF cannot be read or is malformed.
    """
    from upm.core.fileio import atomic_write_text
    from upm.motion.asf import read_asf

    asf_path = Path(asf_path)
    try:
        data = asf_path.read_bytes()
    except OSError as exc:
        raise DataFileError(asf_path, f"cannot read the ASF: {exc.strerror or exc}") from None
    key = digest(data, generator_digest())
    path = cache_dir("models") / f"humanoid-{_safe(asf_path.stem)}-{key}.xml"
    if not path.exists():
        atomic_write_text(path, build_mjcf(read_asf(asf_path)))
    return path


def catalog_model_path(catalog, name: str) -> Path:
    """The cached model of a subject of a :class:`upm.motion.catalog.Catalog`.

    Parameters
    ----------
    catalog : upm.motion.catalog.Catalog
    name : str
        A subject (``"02"``) or a clip (``"02_01"``: its subject's model).
    """
    subject = catalog.info(name).subject if name in catalog else name
    asf = catalog.root / subject / f"{subject}.asf"
    if not asf.exists():
        subjects = sorted({info.subject for info in catalog}, key=_subject_key)
        raise UsageError(f"no subject or clip {name!r} under {catalog.root} "
                         f"(subjects: {', '.join(subjects)})")
    return subject_model_path(asf)


def load_model(path: str | os.PathLike, strength: float = 1.0):
    """Compile an MJCF file (``mujoco.MjModel``), with a one-line error if it fails.

    Parameters
    ----------
    path : path-like
    strength : float
        Every actuator's torque limit (``forcerange``) is multiplied by this (> 0): 1 is
        the strength tables' strong adult (:mod:`humanoid_xml.strength`), 1.5 a body half
        as strong again. The servos' gains are kept.
    """
    import math

    import mujoco

    if not (math.isfinite(strength) and strength > 0):
        raise ValueError(f"strength must be a finite number above 0, not {strength!r}")
    try:
        model = mujoco.MjModel.from_xml_path(os.fspath(path))
    except (ValueError, mujoco.FatalError) as exc:
        message = " ".join(str(exc).split())
        raise DataFileError(path, f"MuJoCo cannot load it: {message}") from None
    model.actuator_forcerange[:] *= strength
    return model


def _safe(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text) or "model"


def _subject_key(subject: str):
    return (int(subject), subject) if subject.isdigit() else (10 ** 9, subject)
