"""Issues 7 and 13, unknown dynamics: the study behind docs/guarantees.md's figures (a script).

    python tests/study_unknown_dynamics.py [RUNS_PER_CASE] [--out results.json]
    python tests/study_unknown_dynamics.py --declared [RUNS_PER_CASE] [--out results.json]
    python tests/study_unknown_dynamics.py --sweeps    # 1-D sweeps of lambda(g) and |f|

Default mode (issue 7, extended by issue 13): draws plants ``x_dot = f(x) + g(x) u + w``
(:func:`test_hard_support.unknown_plant`) over wide ranges, runs the generated C
controller of each bundled case (its default gain, 1 kHz) against them, and classifies
every failure by rerunning it: with ``rate_hz`` doubled and quadrupled (sampling-rate
limit), with the gain divided by ``|g|_2`` when ``|g|_2 > 1``, else a limit of the method.
Each run also gets the verdict of the sampled-data check
(:func:`stt_codegen.verify.sampled.check_sampled`) for the plant's own bounds: a plant
the check accepts must not fail.

``--declared`` (issue 13): one set of declared bounds, :data:`DECLARED`; for each case the
gain is derived from them and the rate is the lowest that passes the check
(:func:`stt_codegen.verify.sampled.lowest_rate`); plants are drawn within the bounds
(:func:`test_plants_support.plant_within`). Every run must hold.

Seeded: the same runs every time. Prints a summary; ``--out`` writes every run as JSON.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

CASES = ("omnirobot-s1", "omnirobot-s2", "omnirobot-s3")
RANGES = {"f_amp": (0.0, 3.0), "f_lin": (0.0, 1.0), "g_min": (0.05, 1.0),
          "g_max_over_min": (1.0, 6.0), "skew": (0.0, 1.0), "w_amp": (0.0, 0.5)}

_CACHE: dict = {}
#: The bounds declared in ``--declared`` mode (``[assumptions]``): input_gain, skew,
#: coupling, drift (|f|), disturbance (|w|).
DECLARED = {"input_gain": (0.5, 2.0), "input_gain_skew": 0.05, "input_gain_coupling": 0.1,
            "drift_bound": 1.0, "disturbance_bound": 0.3}


def _designed(case):
    if case not in _CACHE:
        from stt_codegen.design.search import design_tube
        from stt_codegen.spec.loader import load_spec
        spec = load_spec(case)
        _CACHE[case] = (spec, design_tube(spec).tube)
    return _CACHE[case]


def draw(case: str, index: int) -> dict:
    rng = np.random.default_rng([CASES.index(case), index, 7])
    r = {k: float(rng.uniform(*v)) for k, v in RANGES.items()}
    g_max = r["g_min"] * r["g_max_over_min"]
    return {"f_amp": r["f_amp"], "f_lin": r["f_lin"], "g_min": r["g_min"], "g_max": g_max,
            "skew": r["skew"], "w_amp": r["w_amp"], "seed": [CASES.index(case), index]}


def run_one(case: str, knobs: dict, rate_factor: float = 1.0, gain_factor: float = 1.0):
    from stt_codegen.runtime.simulate import run_closed_loop
    from test_hard_support import plant_bounds, random_plant_parameters, unknown_plant
    spec, design = _designed(case)
    rng = np.random.default_rng(knobs["seed"])
    p = random_plant_parameters(rng, knobs["f_amp"], knobs["f_lin"], knobs["g_min"],
                                knobs["g_max"], knobs["skew"], knobs["w_amp"])
    bounds = plant_bounds(p, spec)
    if rate_factor != 1.0 or gain_factor != 1.0:
        spec = dataclasses.replace(spec, rate_hz=spec.rate_hz * rate_factor)
        design = dataclasses.replace(design, rate_hz=design.rate_hz * rate_factor,
                                     gain=design.gain * gain_factor)
    result = run_closed_loop(spec, design, backend="c", plant=unknown_plant(p, bounds["centre"]))
    verdict = None
    if rate_factor == 1.0 and gain_factor == 1.0:
        verdict = _check_own_bounds(case, p, spec)
    return {"satisfied": bool(result.satisfied), "in_tube": bool(result.stayed_in_tube),
            "check_accepts": verdict,
            "collision": bool(result.collision), "reached": bool(result.reached),
            "left": bool(result.left_state_space),
            "f_inf": bounds["f_inf"], "g_sym_min": bounds["g_sym_min"],
            "g_sym_max": bounds["g_sym_max"], "g_norm": bounds["g_norm"]}


def own_bounds(p: dict, spec):
    """The declared bounds that fit a drawn plant (:func:`test_hard_support.unknown_plant`)."""
    from stt_codegen.spec.loader import Assumptions
    from test_hard_support import _skew
    n = spec.dimension
    eig = np.linalg.eigvalsh(p["sym"])
    k_mat = _skew(p["skew_axis"])
    off = p["sym"] - np.diag(np.diag(p["sym"]))
    coupling = float(np.max(np.linalg.norm(off, axis=1)
                            + p["skew"] * np.linalg.norm(k_mat, axis=1)))
    half = (np.array(spec.state_space.upper) - np.array(spec.state_space.lower)) / 2
    drift = p["f_amp"] * np.sqrt(n) + np.linalg.norm(p["L"], 2) * np.linalg.norm(half)
    return Assumptions((float(eig[0]), float(eig[-1])), float(p["skew"]), coupling,
                       float(drift), float(p["w_amp"] * np.sqrt(n)))


def _check_own_bounds(case, p, spec) -> bool:
    from stt_codegen.design.samples import sample_tube
    from stt_codegen.verify.sampled import check_sampled
    _, design = _designed(case)
    key = ("samples", case)
    if key not in _CACHE:
        _CACHE[key] = sample_tube(design)
    bounds = own_bounds(p, spec)
    if bounds.input_gain[0] <= 0:
        return False
    return bool(check_sampled(design, _CACHE[key], bounds).passed)


def study(args) -> dict:
    case, index = args
    knobs = draw(case, index)
    first = run_one(case, knobs)
    row = {"case": case, "index": index, **knobs, **first, "class": "ok", "reruns": {}}
    if first["in_tube"] and not first["satisfied"]:
        row["class"] = "BUG: in the tube but the task failed"
    if first["satisfied"] and first["in_tube"]:
        return row
    for factor in (2.0, 4.0, 8.0):
        again = run_one(case, knobs, rate_factor=factor)
        row["reruns"][f"rate x{factor:g}"] = again["satisfied"] and again["in_tube"]
        if again["satisfied"] and again["in_tube"]:
            row["class"] = f"sampling: holds at {factor:g}x rate"
            return row
    if first["g_norm"] > 1.0:
        again = run_one(case, knobs, gain_factor=1.0 / first["g_norm"])
        row["reruns"]["gain / |g|"] = again["satisfied"] and again["in_tube"]
        if again["satisfied"] and again["in_tube"]:
            row["class"] = "gain: holds with k / |g|_2"
            return row
    if row["class"] == "ok":
        row["class"] = "method: fails at 8x rate" + (" and with k / |g|_2"
                                                     if first["g_norm"] > 1 else "")
    return row


def sweep_one(args):
    """One point of the 1-D sweeps: ``g = lam I`` (f = 0) or ``f`` constant (g = I)."""
    from stt_codegen.runtime.simulate import run_closed_loop
    from test_hard_support import unknown_plant
    case, kind, value, rate_factor = args
    spec, design = _designed(case)
    n = spec.dimension
    lam, f_const = (value, 0.0) if kind == "g" else (1.0, value)
    p = {"W": np.zeros((n, n)), "phi": np.array([np.pi / 2, -np.pi / 2, np.pi / 2]),
         "f_amp": f_const, "L": np.zeros((n, n)), "sym": lam * np.eye(n),
         "skew_axis": np.array([1.0, 0, 0]), "skew": 0.0, "v": np.zeros(n), "w_amp": 0.1,
         "omega": np.array([1.0, 2.0, 3.0]), "w_phase": np.zeros(n)}
    if rate_factor != 1.0:
        spec = dataclasses.replace(spec, rate_hz=spec.rate_hz * rate_factor)
        design = dataclasses.replace(design, rate_hz=design.rate_hz * rate_factor)
    centre = (np.array(spec.state_space.lower) + np.array(spec.state_space.upper)) / 2
    r = run_closed_loop(spec, design, backend="c", plant=unknown_plant(p, centre))
    return case, kind, value, rate_factor, bool(r.satisfied and r.stayed_in_tube)


def sweeps() -> None:
    points = [(c, "g", v, 1.0) for c in CASES for v in (1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 6.0)]
    points += [(c, "g", v, 2.0) for c in CASES for v in (3.0, 4.0, 6.0)]
    points += [(c, "f", v, 1.0) for c in CASES for v in (2.0, 5.0, 10.0, 15.0, 20.0, 30.0, 50.0)]
    points += [(c, "f", v, 2.0) for c in CASES for v in (20.0, 30.0, 50.0)]
    with ProcessPoolExecutor() as pool:
        results = list(pool.map(sweep_one, points))
    for case in CASES:
        for kind, label in (("g", "g = lam I, f = 0, |w| 0.1"), ("f", "g = I, |f_i| const")):
            cells = [f"{v:g}{'' if r == 1 else f'@{r:g}x'}:{'ok' if good else 'FAIL'}"
                     for c, k, v, r, good in results if c == case and k == kind]
            print(f"{case} {label}: {' '.join(cells)}")


def _declared_setup(case):
    """``(spec, design at the lowest rate, samples)`` for :data:`DECLARED`, cached."""
    key = ("declared", case)
    if key not in _CACHE:
        from stt_codegen.verify.sampled import lowest_rate
        from stt_codegen.spec.loader import Assumptions
        spec, design = _designed(case)
        a = Assumptions(DECLARED["input_gain"], DECLARED["input_gain_skew"],
                        DECLARED["input_gain_coupling"], DECLARED["drift_bound"],
                        DECLARED["disturbance_bound"])
        rate, gain = lowest_rate(design, spec, a)
        if rate is None:
            raise SystemExit(f"{case}: no rate passes the sampled check for {DECLARED}")
        spec = dataclasses.replace(spec, rate_hz=rate, assumptions=a)
        _CACHE[key] = (spec, dataclasses.replace(design, rate_hz=rate, gain=gain))
    return _CACHE[key]


def declared_one(args) -> dict:
    """One plant within :data:`DECLARED` on one case, at the derived gain and rate."""
    from stt_codegen.runtime.simulate import run_closed_loop
    from test_plants_support import plant_system, plant_within
    case, index = args
    spec, design = _declared_setup(case)
    rng = np.random.default_rng([CASES.index(case), index, 13])
    plant = plant_system(plant_within(rng, spec.assumptions, spec.state_space))
    r = run_closed_loop(spec, design, backend="c", plant=plant)
    return {"case": case, "index": index, "rate_hz": design.rate_hz, "gain": design.gain,
            "satisfied": bool(r.satisfied), "in_tube": bool(r.stayed_in_tube),
            "collision": bool(r.collision), "left": bool(r.left_state_space)}


def declared(runs: int, out: str | None) -> int:
    jobs = [(case, i) for case in CASES for i in range(runs)]
    start = time.perf_counter()
    for case in CASES:
        spec, design = _declared_setup(case)
        print(f"{case}: declared {DECLARED}: rate {design.rate_hz:g} Hz, gain {design.gain:.4g}")
    with ProcessPoolExecutor() as pool:
        rows = list(pool.map(declared_one, jobs, chunksize=4))
    held = sum(r["satisfied"] and r["in_tube"] for r in rows)
    print(f"{len(rows)} plants within the declared bounds ({runs} per case) in "
          f"{time.perf_counter() - start:.0f} s: {held} hold, {len(rows) - held} fail")
    if out:
        Path(out).write_text(json.dumps(rows, indent=1))
    return 0 if held == len(rows) else 1


def main(argv: list[str]) -> int:
    if "--sweeps" in argv:
        sweeps()
        return 0
    if "--declared" in argv:
        rest = [a for a in argv if a != "--declared"]
        runs = int(rest[0]) if rest and not rest[0].startswith("-") else 100
        return declared(runs, rest[rest.index("--out") + 1] if "--out" in rest else None)
    runs = int(argv[0]) if argv and not argv[0].startswith("-") else 100
    out = argv[argv.index("--out") + 1] if "--out" in argv else None
    jobs = [(case, i) for case in CASES for i in range(runs)]
    start = time.perf_counter()
    with ProcessPoolExecutor() as pool:
        rows = list(pool.map(study, jobs, chunksize=4))
    elapsed = time.perf_counter() - start
    total = len(rows)
    ok = sum(r["class"] == "ok" for r in rows)
    print(f"{total} runs ({runs} per case) in {elapsed:.0f} s: {ok} hold ({100 * ok / total:.1f} %)")
    classes: dict[str, int] = {}
    for r in rows:
        classes[r["class"]] = classes.get(r["class"], 0) + 1
    for name, count in sorted(classes.items(), key=lambda kv: -kv[1]):
        print(f"  {count:5d}  {100 * count / total:5.1f} %  {name}")
    accepted = [r for r in rows if r["check_accepts"]]
    bad = [r for r in accepted if r["class"] != "ok"]
    flagged = [r for r in rows if not r["check_accepts"]]
    print(f"sampled check on each plant's own bounds: accepts {len(accepted)}, of which "
          f"{len(bad)} fail; flags {len(flagged)}, of which "
          f"{sum(r['class'] != 'ok' for r in flagged)} fail")
    nominal = [r for r in rows if r["g_norm"] <= 1.0]
    if nominal:
        held = sum(r["class"] == "ok" for r in nominal)
        print(f"|g|_2 <= 1: {held}/{len(nominal)} hold")
    if out:
        Path(out).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
