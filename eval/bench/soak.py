"""The soak (issue 64): the walking sequence looped, root free, by the balance controller,
for an hour of simulated time (``upm bench --only soak``; ``--soak-s`` for another length):
no NaN or divergence, resident memory growing less than 5 % from the 5th minute to the
end, and the wall seconds per simulated second flat minute after minute
(:mod:`eval.soak`). Its own figures are its references: the memory against the memory
at the twelfth of the run, the last minute's pace against the first's.

Quick mode loops the sequence's first second for 4 s (four loops) with buckets of 2 s.
"""

from __future__ import annotations

from eval.bench import BenchContext

NAME = "soak"


def run(context: BenchContext) -> dict:
    from eval.soak import SoakSettings, run_soak
    from upm.core.progress import progress

    if context.quick:
        settings = SoakSettings(str(context.data_dir), duration_s=context.soak_s or 4.0,
                                bucket_s=2.0, loop_s=1.0)
    else:
        duration = context.soak_s or 3600.0
        settings = SoakSettings(str(context.data_dir), duration_s=duration,
                                bucket_s=min(60.0, duration / 4))
    with progress(total=round(settings.duration_s), desc="soak", unit="sim s") as bar:
        def advance(loop: dict) -> None:
            bar.update(min(bar.total, round(loop["sim_end_s"])) - bar.n)

        return run_soak(settings, on_loop=advance)
