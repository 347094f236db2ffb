"""``stt-codegen bench sampled``: law (13)'s per-axis sampled check folded into CasADi's
virtual machine beside the Python loop it is tested against (docs/sampled-data.md, "How
the check is evaluated").

For each spec, its tube (designed without ``[actuator]``) sampled at its rate, and the
per-axis check (``check_sampled(..., lyapunov=False)``) run whole ``runs`` times with
``folded=False`` and ``folded=True`` in turn, so that both share the machine's load; the
least CPU of each is kept, and whether the two results are the same, float for float. The
check's setup (the tube's enclosure, the class's bounds, the peaks) is in both times; the
folded functions are built before the first run.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from .report import table

__all__ = ["DEFAULT_SPECS", "format_sampled_report", "run_sampled_bench"]

#: Bundled cases: two diagonal omnidirectional robots, a coupled one (the per-axis
#: argument, which ``verify`` asks first) and a differential-drive base (whose gains turn
#: with the held command).
DEFAULT_SPECS = ("omnirobot-s3", "crossing-moving", "omnirobot-s1", "office-base")


def _same(a, b) -> bool:
    """Two checks' verdicts, figures and bounds equal float for float."""
    floats = all(x == y or (math.isnan(x) and math.isnan(y))
                 for x, y in ((a.level, b.level), (a.margin, b.margin), (a.time, b.time)))
    bounds = ((a.abs_e is None and b.abs_e is None) or
              (a.abs_e is not None and b.abs_e is not None
               and np.array_equal(a.abs_e, b.abs_e)))
    return (floats and bounds and a.data == b.data
            and (a.passed, a.reason, a.dimension) == (b.passed, b.reason, b.dimension))


def run_sampled_bench(specs=DEFAULT_SPECS, runs: int = 3, delay: float = 0.0) -> dict:
    """Both ways of the per-axis check on each spec's tube.

    Parameters
    ----------
    specs : sequence of str
        Bundled case names or spec files.
    runs : int
        Runs of each, the least CPU kept.
    delay : float
        A computation delay, as a fraction of the period, in ``[0, 1]`` (0: none).

    Returns
    -------
    dict
        ``rows``: per spec ``spec``, ``samples``, ``turns`` (a base), ``passed``, ``loop_s``,
        ``folded_s`` (CPU seconds), ``ratio`` (loop over folded), ``same``.
    """
    import stt_codegen as stt
    from stt_codegen.design.certificate.plant_class import plant_class
    from stt_codegen.design.certificate.sampled import check_sampled
    from stt_codegen.design.failures import without_advice
    from stt_codegen.design.samples import sample_tube
    from stt_codegen.tube import reference

    rows = []
    for name in specs:
        spec = dataclasses.replace(stt.load_spec(name), input_bound=None)
        with without_advice():
            tube = stt.design_tube(spec).tube
        plants = plant_class(spec)
        best = {False: math.inf, True: math.inf}
        found = {}
        lag = delay / tube.rate_hz
        with reference.numpy_math():
            samples = sample_tube(tube)
            check_sampled(tube, samples, plants, lyapunov=False, delay=lag)  # builds
            for _ in range(runs):
                for folded in (False, True):
                    start = time.process_time()
                    found[folded] = check_sampled(tube, samples, plants, lyapunov=False,
                                                  folded=folded, delay=lag)
                    best[folded] = min(best[folded], time.process_time() - start)
        rows.append({"spec": Path(name).stem, "samples": int(len(samples.t)),
                     "turns": plants.assumptions.input_gain_turn is not None,
                     "passed": bool(found[True].passed), "loop_s": best[False],
                     "folded_s": best[True], "ratio": best[False] / best[True],
                     "same": _same(found[False], found[True])})
    return {"runs": runs, "delay": delay, "rows": rows}


def format_sampled_report(report: dict) -> str:
    """The report as a table."""
    delay = (f", a delay of {report['delay']:g} period" if report.get("delay") else "")
    rows = [[r["spec"], str(r["samples"]), "yes" if r["turns"] else "no",
             "yes" if r["passed"] else "no", f"{r['loop_s']:.3f}", f"{r['folded_s']:.3f}",
             f"{r['ratio']:.1f}", "yes" if r["same"] else "NO"] for r in report["rows"]]
    return "\n".join([f"law (13)'s per-axis sampled check{delay}, the loop beside the folded "
                      f"step (CPU, least of {report['runs']} runs each, in turn)",
                      table(["spec", "samples", "base", "passed", "loop [s]", "folded [s]",
                             "ratio", "same"], rows)])
