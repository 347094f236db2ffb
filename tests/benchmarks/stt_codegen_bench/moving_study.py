"""A study of moving obstacles on random arenas: ``python -m stt_codegen_bench.moving_study``.

Arena ``k`` of seed ``S`` (kind ``"moving"`` of :func:`~.arenas.make_arena`: four static 1 m boxes and 0-4
random moving obstacles). For each, the design (:func:`stt_codegen.design_tube`: space-time,
re-timed via, swept) and, as the baseline a user would otherwise take, the *swept-only*
design (every moving obstacle as the static box it sweeps,
:func:`~stt_codegen.design.swept.swept_spec`) are run; each design found is simulated (Python backend, collisions with moving obstacles
where they are). Reported: how each design was found, designed and satisfied counts, and the
design time (median, p95), measured side by side in one run (docs/moving-obstacles.md).
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections import Counter
from typing import Any

import numpy as np

from stt_codegen.design.swept import swept_spec
from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError
from stt_codegen.runtime.simulate import simulate
from stt_codegen.spec.loader import Spec
from .arenas import arena_spec

__all__ = ["study_moving"]


def _run(spec: Spec) -> tuple[str, float, bool]:
    """(how it was designed or ``"no design"``, design seconds, satisfied in closed loop)."""
    started = time.perf_counter()
    try:
        design = design_tube(spec)
    except DesignError:
        return "no design", time.perf_counter() - started, False
    elapsed = time.perf_counter() - started
    return design.motion or "static", elapsed, simulate(design, backend="python").satisfied


def study_moving(count: int, seed: int) -> dict[str, Any]:
    """Run the study on arenas ``0 .. count - 1`` of ``seed`` (see the module notes).

    Parameters
    ----------
    count : int
        Number of arenas.
    seed : int
        Arena seed, >= 0 (also seeds the moving obstacles of each arena).

    Returns
    -------
    dict
        ``arenas``, ``moving_obstacles`` (total drawn), ``stt`` and ``swept_only``: each
        ``designed``, ``satisfied``, ``how`` (counts per way found), ``design_ms_median``,
        ``design_ms_p95``.
    """
    rows: dict[str, list[tuple[str, float, bool]]] = {"stt": [], "swept_only": []}
    drawn = 0
    for k in range(count):
        spec = arena_spec("moving", seed, k)
        drawn += len(spec.moving_obstacles)
        rows["stt"].append(_run(spec))
        swept, _ = swept_spec(spec) if spec.moving_obstacles else (spec, "")
        if swept is None:
            rows["swept_only"].append(("no design", 0.0, False))
        else:
            how, seconds, ok = _run(swept)
            # judged against the swept boxes, which hold every position of the moving ones
            rows["swept_only"].append((how, seconds, ok))
    out: dict[str, Any] = {"arenas": count, "seed": seed, "moving_obstacles": drawn}
    for name, results in rows.items():
        times = sorted(1e3 * s for how, s, _ in results if how != "no design")
        out[name] = {
            "designed": sum(how != "no design" for how, _, _ in results),
            "satisfied": sum(ok for _, _, ok in results),
            "how": dict(sorted(Counter(how for how, _, _ in results).items())),
            "design_ms_median": statistics.median(times) if times else None,
            "design_ms_p95": float(np.percentile(times, 95)) if times else None}
    return out


def main(argv: list[str] | None = None) -> int:
    """Print the study for ``--count`` arenas of ``--seed``."""
    parser = argparse.ArgumentParser(prog="python -m stt_codegen_bench.moving_study")
    parser.add_argument("--count", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    result = study_moving(args.count, args.seed)
    print(f"{result['arenas']} arenas of seed {result['seed']}, "
          f"{result['moving_obstacles']} moving obstacles in all")
    for name in ("stt", "swept_only"):
        r = result[name]
        median = "-" if r["design_ms_median"] is None else f"{r['design_ms_median']:.1f}"
        p95 = "-" if r["design_ms_p95"] is None else f"{r['design_ms_p95']:.1f}"
        print(f"{name:<11} designed {r['designed']:>3}  satisfied {r['satisfied']:>3}  "
              f"design ms median {median} p95 {p95}  how {r['how']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
