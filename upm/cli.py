"""The ``upm`` command line.

Every subcommand lives in its own module, named in :data:`COMMANDS`, with

- ``HELP``: a one-line summary, and the module docstring as its description;
- ``configure(parser)``: adds its arguments (no heavy imports at module level);
- ``run(args) -> int``: does the work, importing MuJoCo and friends only here.

Bad input (an :class:`~upm.errors.UpmError`, a bad argument, an unwritable output)
prints one line on stderr and exits 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings

from upm.errors import UpmError

#: Subcommand name -> module implementing it, in the order ``upm --help`` lists them.
COMMANDS: dict[str, str] = {
    "clips": "upm.commands.clips",
    "train": "upm.commands.train",
    "map-info": "upm.commands.map_info",
    "bench": "upm.commands.bench",
    "transition": "upm.commands.transition",
    "sequence": "upm.commands.sequence",
    "model": "upm.commands.model",
    "check": "upm.commands.check",
    "simulate": "upm.commands.simulate",
    "eval": "upm.commands.eval",
    "studio": "upm.commands.studio",
}


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line on stderr, exit code 2."""

    def error(self, message):  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    return f"upm: warning: {message}\n"


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="upm",
        description="Uniform Posture Map motion transitions (Lee & Chung 2001) on CMU motion "
        "capture, checked for physical validity on a MuJoCo humanoid.",
        epilog="Data: --data DIR, default $UPM_DATA (the CMU clips, e.g. ../shared/data/cmu). "
        "A CLIP is a name such as 02_01; CLIP@F is frame F (0-based), CLIP@A:B frames A to B-1.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    subparsers.required = True
    for name, module_name in COMMANDS.items():
        module = importlib.import_module(module_name)
        sub = subparsers.add_parser(
            name, help=module.HELP, description=module.__doc__,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        module.configure(sub)
        sub.set_defaults(_run=module.run)
    return parser


def _limit_blas_threads() -> None:
    """One BLAS thread, unless the user chose a number (OMP/OPENBLAS/MKL_NUM_THREADS).

    The arrays here are small (a window of 20-40 frames x 63 DOFs): a multi-threaded BLAS
    only adds contention; the spacetime optimisation ran 2-30x slower with it on a loaded
    2-core machine.
    """
    import os

    names = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
    if any(os.environ.get(v) for v in names):
        return
    # Libraries loaded later (scipy's own OpenBLAS, worker processes) read the variables;
    # the ones already loaded (numpy's) are limited through threadpoolctl.
    for v in names:
        os.environ[v] = "1"
    from threadpoolctl import threadpool_limits

    threadpool_limits(1, user_api="blas")


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    warnings.formatwarning = _one_line_warning
    _limit_blas_threads()
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args._run(args) or 0)
    except UpmError as exc:
        print(f"upm {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        target = f" {exc.filename}" if exc.filename else ""
        print(f"upm {args.command}: error:{target}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"upm {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
