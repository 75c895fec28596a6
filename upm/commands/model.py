"""Write the MuJoCo humanoid (MJCF) of a skeleton.

The model has a body per ASF bone at the skeleton's own offsets (z up), one hinge per
DOF the ASF declares for the 21 posture joints (range = the human range of motion), capsule geoms
with a plausible adult mass, self-collision, and a position actuator per hinge. Give one
of:

  --asf FILE       any ASF skeleton (e.g. a CMU subject's NN.asf)
  --subject NAME   a subject (02) or clip (02_01) of the data directory (--data)
  --generic        the default model: the generic adult, built from the description
                   the package owns (identical to the packaged generic_adult.xml)

With --out the model is written there (atomically); without it, a subject's model is
built into the cache (outside the repository) and its path printed. Open a model with
`python -m mujoco.viewer --mjcf FILE.xml`.
"""

from __future__ import annotations

from upm.commands.common import add_data_argument, print_json

HELP = "write the MuJoCo humanoid (MJCF) of an ASF skeleton, a subject, or the generic adult"


def configure(parser) -> None:
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--asf", metavar="FILE", help="an ASF skeleton file")
    source.add_argument("--subject", metavar="NAME",
                        help="a subject (e.g. 02) or clip (e.g. 02_01) under --data")
    source.add_argument("--generic", action="store_true",
                        help="the default model: the generic adult (1.75 m tables)")
    add_data_argument(parser)
    parser.add_argument("--out", metavar="FILE.xml", default=None,
                        help="where to write the model (default: the cache; path printed)")
    parser.add_argument("--json", action="store_true",
                        help="print a JSON summary (path, nq, nv, nu, mass) instead of a line")


def run(args) -> int:
    import re
    from pathlib import Path

    import numpy as np

    import humanoid_xml
    from upm.core.errors import UsageError
    from upm.core.fileio import atomic_write_text

    if args.generic:
        # Rebuilt from the description the project owns (identical to the packaged file,
        # which a test checks): so `--generic --out` is also how that file is regenerated.
        source = humanoid_xml.default_model_path()
        text = humanoid_xml.build_mjcf(humanoid_xml.generic_skeleton())
    elif args.asf:
        if not Path(args.asf).is_file():
            raise UsageError(f"--asf {args.asf}: no such file")
        source = humanoid_xml.subject_model_path(args.asf)
        text = source.read_text(encoding="utf-8")
    else:
        from upm.motion.catalog import Catalog

        source = humanoid_xml.catalog_model_path(Catalog(args.data), args.subject)
        text = source.read_text(encoding="utf-8")
    path = Path(args.out) if args.out else source
    if args.out:
        atomic_write_text(path, text)
    model = humanoid_xml.load_model(path)
    summary = {
        "path": str(path),
        "model": re.search(r'<mujoco model="([^"]*)"', text).group(1),
        "bodies": int(model.nbody - 1),
        "nq": int(model.nq),
        "nv": int(model.nv),
        "nu": int(model.nu),
        "mass_kg": round(float(np.sum(model.body_mass)), 2),
    }
    if args.json:
        print_json(summary)
    else:
        print(f"{path}: {summary['model']}, {summary['bodies']} bodies, nq {summary['nq']}, "
              f"nv {summary['nv']}, nu {summary['nu']}, mass {summary['mass_kg']:.1f} kg")
    return 0
