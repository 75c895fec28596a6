"""The ``upm`` command line.

Every subcommand lives in its own module, named in :data:`COMMANDS`, with

- ``HELP``: a one-line summary, and the module docstring as its description;
- ``configure(parser)``: adds its arguments (no heavy imports at module level);
- ``run(args) -> int``: does the work, importing MuJoCo and friends only here.

Bad input (an :class:`~upm.core.errors.UpmError`, a bad argument, an unwritable output)
prints one line on stderr and exits 2.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import sys
import warnings

from upm.core.errors import UpmError

#: Subcommand name -> module implementing it, in the order ``upm --help`` lists them.
COMMANDS: dict[str, str] = {
    "clips": "upm.commands.clips",
    "train": "upm.commands.train",
    "map-info": "upm.commands.map_info",
    "bench": "upm.commands.bench",
    "transition": "upm.commands.transition",
    "sequence": "upm.commands.sequence",
    "convert": "upm.commands.convert",
    "model": "upm.commands.model",
    "check": "upm.commands.check",
    "calibrate": "upm.commands.calibrate",
    "simulate": "upm.commands.simulate",
    "eval": "upm.commands.eval",
    "robustness": "upm.commands.robustness",
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
        epilog="Data: --data DIR, default $UPM_DATA, else shared/data/cmu beside the checkout "
        "(the CMU clips). A CLIP is a name such as 02_01; CLIP@F is frame F (0-based), "
        "CLIP@A:B frames A to B-1 (either end may be left out); in every command a negative "
        "frame counts from the end (CLIP@-1 is the last frame, CLIP@-60: the last 60). A clip "
        "without a frame rate in clips.csv is read at 120 fps with a warning.",
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


_BLAS_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


@contextlib.contextmanager
def _command_environment():
    """The process-wide settings of one command's run, restored when it ends.

    - Warnings print as one line (``upm: warning: ...``).
    - One BLAS thread, unless the user chose a number (OMP/OPENBLAS/MKL_NUM_THREADS).
      The arrays here are small (a window of 20-40 frames x 63 DOFs): a multi-threaded
      BLAS only adds contention; the spacetime optimisation ran 2-30x slower with it on a
      loaded 2-core machine. Libraries loaded later (scipy's own OpenBLAS, worker
      processes) read the variables; the ones already loaded (numpy's) are limited
      through threadpoolctl.

    Tests call :func:`main` in-process, so nothing here may outlive the command.
    """
    import os

    saved_format = warnings.formatwarning
    saved_env = {v: os.environ.get(v) for v in _BLAS_THREAD_VARIABLES}
    user_chose = any(saved_env.values())
    warnings.formatwarning = _one_line_warning
    try:
        if user_chose:
            yield
            return
        for v in _BLAS_THREAD_VARIABLES:
            os.environ[v] = "1"
        from threadpoolctl import threadpool_limits

        with threadpool_limits(1, user_api="blas"):
            yield
    finally:
        warnings.formatwarning = saved_format
        for v, value in saved_env.items():
            if value is None:
                os.environ.pop(v, None)
            else:
                os.environ[v] = value


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code.

    Exit codes: 0 success, 2 bad input (one line on stderr), 130 interrupted, 141 when
    the reader of stdout went away (``upm clips | head``: no message).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with _command_environment():
            code = int(args._run(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not at the interpreter's exit
        return code
    except BrokenPipeError:
        _silence_stdout()
        return 141
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


def _silence_stdout() -> None:
    """After a closed pipe: point stdout at /dev/null so the interpreter's final flush
    does not raise again (the recipe of Python's ``signal`` documentation)."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # stdout replaced, or no descriptor
        pass


if __name__ == "__main__":
    sys.exit(main())
