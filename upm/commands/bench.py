"""Measure the performance figures and print them as JSON.

Every figure stands next to a reference measured in the same run on the same machine
(for example raw MuJoCo mj_step throughput, or a plain cKDTree query), with the ratio,
since absolute timings vary between machines. BLAS is pinned to one thread for the whole
run, whatever the environment says: small-array work slows down with more threads on a
loaded machine, and a figure and its reference must run alike.
"""

from __future__ import annotations

HELP = "performance figures as JSON (each with a same-run reference and a ratio)"


def configure(parser) -> None:
    from upm.commands.common import add_data_argument

    add_data_argument(parser)
    parser.add_argument("--only", nargs="+", metavar="NAME", default=None,
                        help="run only these benchmarks (default: all)")
    parser.add_argument("--quick", action="store_true",
                        help="fewer repetitions and smaller inputs (rougher figures)")
    parser.add_argument("--soak-s", type=float, default=None, metavar="SECONDS",
                        help="simulated seconds of the soak (the walking sequence looped, root "
                        "free; default 3600, with --quick 4)")
    parser.add_argument("--out", metavar="FILE.json", default=None,
                        help="also write the JSON to this file")


def run(args) -> int:
    import json
    import math
    import platform
    import sys

    from threadpoolctl import threadpool_info, threadpool_limits

    from eval.bench import BenchContext, discover, missed_targets
    from upm.commands.common import print_json
    from upm.core.errors import UsageError
    from upm.core.fileio import atomic_write_text
    from upm.core.progress import progress
    from upm.motion.catalog import Catalog

    if args.soak_s is not None and not (args.soak_s > 0 and math.isfinite(args.soak_s)):
        raise UsageError(f"--soak-s {args.soak_s}: give a positive number of seconds")
    catalog = Catalog(args.data)
    modules = discover()
    names = args.only or list(modules)
    unknown = [n for n in names if n not in modules]
    if unknown:
        raise UsageError(f"no benchmark {unknown[0]!r} (known: {', '.join(modules)})")
    context = BenchContext(data_dir=catalog.root, quick=args.quick, soak_s=args.soak_s)
    report = {
        "schema": 1,
        "machine": {"python": platform.python_version(), "processor": platform.machine(),
                    "system": platform.system()},
        "quick": args.quick,
        "benchmarks": {},
    }
    with threadpool_limits(1, user_api="blas"):
        report["blas_threads"] = sorted({p["num_threads"] for p in threadpool_info()
                                         if p["user_api"] == "blas"})
        for name in progress(names, desc="benchmarks", unit="bench"):
            report["benchmarks"][name] = modules[name].run(context)
    if args.out:
        atomic_write_text(args.out, json.dumps(report, indent=2) + "\n")
    print_json(report)
    for line in missed_targets(report):
        print(line, file=sys.stderr)
    return 0
