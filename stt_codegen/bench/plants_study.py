"""The wide study of unknown plants: simulation against the sampled check.

Draws plants ``x_dot = f(x) + g(x) u + w`` over wide ranges (``|f|`` up to about 6,
eigenvalues of the symmetric part of ``g`` in ``[0.05, 5]``, a skew part up to 1,
``|w_i| <= 0.5``), runs the generated C controller of each bundled case (its design's gain
and rate) against each, and asks the sampled check
(:func:`~stt_codegen.verify.sampled.check_sampled`) whether it proves that plant's own
bounds. A plant the check accepts must hold in simulation; the study reports how many of
the plants that hold the check accepts.

The plants and seeds are those of the former ``tests/study_unknown_dynamics.py`` (issue
7), which this module replaces, so that the numbers compare. Run::

    python -m stt_codegen.bench.plants_study [RUNS_PER_CASE] [--workers W] [--out rows.json]
                                             [--classes] [--own-gain]

``--classes`` also searches each plant's class (its own bounds) for a member that leaves
the tube (:func:`~stt_codegen.verify.class_search.search_class`): no sound check may accept
a class with such a member, so the study then says how many of the plants that hold any
sound check could accept at most, and how many of those the check accepts. ``--own-gain``
runs everything at the gain the design derives from each plant's own bounds, as a user who
declared them in ``[assumptions]`` would get, instead of the bundled design's gain.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..design.gain import derived_gain
from ..design.samples import sample_tube
from ..design.search import design_tube
from ..runtime.simulate import run_closed_loop
from ..spec.assumptions import Assumptions
from ..spec.loader import load_spec
from ..verify.sampled import check_sampled
from ..verify.class_search import replay, search_class, unit_skew

__all__ = ["CASES", "RANGES", "draw", "plant_parameters", "own_bounds", "study_one",
           "study_plants"]

CASES = ("omnirobot-s1", "omnirobot-s2", "omnirobot-s3")
#: Ranges of the drawn knobs (uniform): sinusoidal drift amplitude, linear drift's spectral
#: norm, ``g_min``, ``g_max / g_min``, skew amplitude, disturbance amplitude per state.
RANGES = {"f_amp": (0.0, 3.0), "f_lin": (0.0, 1.0), "g_min": (0.05, 1.0),
          "g_max_over_min": (1.0, 6.0), "skew": (0.0, 1.0), "w_amp": (0.0, 0.5)}


@lru_cache(maxsize=None)
def _designed(case: str):
    spec = load_spec(case)
    design = design_tube(spec).tube
    return spec, design, sample_tube(design)


@lru_cache(maxsize=None)
def _min_width(case: str) -> float:
    """The certified narrowest width of the case's design, from which its gain is derived."""
    return design_tube(load_spec(case)).check.min_width


def draw(case: str, index: int) -> dict:
    """The knobs of plant ``index`` of ``case`` (seeded by both).

    Parameters
    ----------
    case : str
        One of :data:`CASES`.
    index : int
        The plant's number within the case.

    Returns
    -------
    dict
        A value in each range of :data:`RANGES` (``g_max`` as ``g_min`` times the drawn
        ratio) and ``seed``, the pair that seeds :func:`plant_parameters`.
    """
    rng = np.random.default_rng([CASES.index(case), index, 7])
    r = {k: float(rng.uniform(*v)) for k, v in RANGES.items()}
    return {"f_amp": r["f_amp"], "f_lin": r["f_lin"], "g_min": r["g_min"],
            "g_max": r["g_min"] * r["g_max_over_min"], "skew": r["skew"], "w_amp": r["w_amp"],
            "seed": [CASES.index(case), index]}


def plant_parameters(knobs: dict, n: int = 3) -> dict:
    """``f(x) = f_amp sin(W x + phi) + L (x - c)``, ``g(x) = S + skew tanh(v . x) K``,
    ``w_i = w_amp sin(omega_i t + p_i)``; ``S`` symmetric with eigenvalues in
    ``[g_min, g_max]`` (both reached), ``K`` a unit skew matrix.

    Parameters
    ----------
    knobs : dict
        From :func:`draw`.
    n : int, optional
        State dimension.

    Returns
    -------
    dict
        ``W`` (n, n), ``phi`` (n,), ``f_amp``, ``L`` (n, n) of the drift; ``sym`` (n, n),
        ``skew_axis`` (n,), ``skew``, ``v`` (n,) of the input matrix; ``w_amp``, ``omega``
        (n,) rad/s and ``w_phase`` (n,) of the disturbance.
    """
    rng = np.random.default_rng(knobs["seed"])
    q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    eig = rng.uniform(knobs["g_min"], knobs["g_max"], n)
    eig[0], eig[-1] = knobs["g_min"], knobs["g_max"]
    lin = rng.normal(size=(n, n))
    lin = lin / np.linalg.norm(lin, 2)
    axis = rng.normal(size=n)
    return {"W": rng.normal(size=(n, n)), "phi": rng.uniform(0, 2 * np.pi, n),
            "f_amp": knobs["f_amp"], "L": knobs["f_lin"] * lin,
            "sym": q @ np.diag(eig) @ q.T, "skew_axis": axis / np.linalg.norm(axis),
            "skew": knobs["skew"], "v": rng.normal(size=n), "w_amp": knobs["w_amp"],
            "omega": rng.uniform(0.2, 5.0, n), "w_phase": rng.uniform(0, 2 * np.pi, n)}


def _system(p: dict, centre: np.ndarray):
    import control as ct
    k_mat = unit_skew(p["skew_axis"])

    def rhs(t, x, u, params):
        f = p["f_amp"] * np.sin(p["W"] @ x + p["phi"]) + p["L"] @ (x - centre)
        g = p["sym"] + p["skew"] * np.tanh(p["v"] @ x) * k_mat
        w = p["w_amp"] * np.sin(p["omega"] * t + p["w_phase"])
        return f + g @ np.asarray(u, float) + w

    n = len(centre)
    return ct.nlsys(rhs, None, inputs=n, states=n, outputs=n)


def own_bounds(p: dict, spec) -> Assumptions:
    """The bounds a user who knew the drawn plant would declare (over the state space).

    Parameters
    ----------
    p : dict
        The plant, from :func:`plant_parameters`.
    spec : Spec
        Gives the state space the drift is bounded over.

    Returns
    -------
    Assumptions
        ``input_gain`` (the extreme eigenvalues of ``S``), ``input_gain_skew``,
        ``input_gain_coupling``, ``drift_bound`` and ``disturbance_bound`` (Euclidean, over
        the state space).
    """
    n = spec.dimension
    eig = np.linalg.eigvalsh(p["sym"])
    k_mat = unit_skew(p["skew_axis"])
    off = p["sym"] - np.diag(np.diag(p["sym"]))
    coupling = float(np.max(np.linalg.norm(off, axis=1)
                            + p["skew"] * np.linalg.norm(k_mat, axis=1)))
    half = (np.array(spec.state_space.upper) - np.array(spec.state_space.lower)) / 2
    drift = p["f_amp"] * math.sqrt(n) + np.linalg.norm(p["L"], 2) * np.linalg.norm(half)
    return Assumptions((float(eig[0]), float(eig[-1])), float(p["skew"]), coupling,
                       float(drift), float(p["w_amp"] * math.sqrt(n)))


def _holds(case: str, p: dict, rate_factor: float = 1.0, gain: float | None = None) -> bool:
    spec, design, _ = _designed(case)
    if gain is not None:
        design = dataclasses.replace(design, gain=gain)
    if rate_factor != 1.0:
        spec = dataclasses.replace(spec, rate_hz=spec.rate_hz * rate_factor)
        design = dataclasses.replace(design, rate_hz=design.rate_hz * rate_factor)
    centre = (np.array(spec.state_space.lower) + np.array(spec.state_space.upper)) / 2
    result = run_closed_loop(spec, design, backend="c", plant=_system(p, centre))
    return bool(result.satisfied and result.stayed_in_tube)


def study_one(job: tuple) -> dict:
    """One plant: whether it holds in simulation, the check's verdict on its own bounds,
    and, when it fails, whether it holds at 2, 4 or 8 times the rate.

    ``job`` is ``(case, index)``, ``(case, index, classes)`` or ``(case, index, classes,
    own_gain)``. With ``classes`` true, the row's ``class_counterexample`` is a member of
    the plant's class that leaves the tube
    (:meth:`~stt_codegen.verify.class_search.Counterexample.to_json`), or ``None`` when the
    search finds none. With ``own_gain`` true, the gain of law (13) is the one the design
    derives from the plant's own bounds (:func:`~stt_codegen.design.gain.derived_gain` at
    the design's certified narrowest width), as if the user had declared them in
    ``[assumptions]``, for the check, the search and the simulation alike; otherwise it is
    the bundled design's (derived from the robot's bounds).

    Parameters
    ----------
    job : tuple
        ``(case, index[, classes[, own_gain]])``: a case of :data:`CASES`, the plant's index
        and two bools (default ``False``).

    Returns
    -------
    dict
        The knobs and ``held``, ``check_accepts``, ``check_s`` (s), the plant's own bounds
        (``g_min_own``, ``g_max_own``, ``coupling``, ``push``), ``check_fails_at`` (s or
        ``None``), ``gain``; with ``classes`` ``class_counterexample``; when it did not hold
        ``holds_at_rate_factor`` (2, 4, 8 or ``None``).
    """
    case, index = job[:2]
    classes, own_gain = (tuple(job[2:]) + (False, False))[:2]
    spec, design, samples = _designed(case)
    knobs = draw(case, index)
    p = plant_parameters(knobs)
    bounds = own_bounds(p, spec)
    gain = derived_gain(_min_width(case), design.rate_hz, bounds) if own_gain else None
    if gain is not None:
        design = dataclasses.replace(design, gain=gain)
    started = time.perf_counter()
    verdict = check_sampled(design, samples, bounds)
    check_s = time.perf_counter() - started
    held = _holds(case, p, gain=gain)
    row = {"case": case, "index": index, **knobs, "held": held,
           "check_accepts": verdict.passed, "check_s": check_s,
           "g_min_own": bounds.input_gain[0], "g_max_own": bounds.input_gain[1],
           "coupling": bounds.input_gain_coupling,
           "push": bounds.drift_bound + bounds.disturbance_bound,
           "check_fails_at": None if verdict.passed else verdict.time,
           "gain": design.gain}
    if classes:
        found = search_class(design, samples, bounds)
        row["class_counterexample"] = (None if found is None else
                                       {**found.to_json(), "replayed_on_c": replay(design, found)})
    if not held:
        row["holds_at_rate_factor"] = next(
            (f for f in (2.0, 4.0, 8.0) if _holds(case, p, f, gain)), None)
    return row


def study_plants(runs: int, workers: int = 2, classes: bool = False,
                 own_gain: bool = False) -> list[dict]:
    """``runs`` plants per bundled case (:func:`study_one`, with the class search when
    ``classes``, at the gain derived from each plant's bounds when ``own_gain``), in
    parallel.

    Parameters
    ----------
    runs : int
        Plants per case.
    workers : int, optional
        Processes; 1 or fewer runs them in this process.
    classes : bool, optional
        Search each plant's class for a counterexample.
    own_gain : bool, optional
        Use the gain derived from each plant's own bounds.

    Returns
    -------
    list of dict
        :func:`study_one`'s rows, case by case, in index order.
    """
    jobs = [(case, i, classes, own_gain) for case in CASES for i in range(runs)]
    if workers <= 1:
        return [study_one(j) for j in jobs]
    with ProcessPoolExecutor(workers) as pool:
        return list(pool.map(study_one, jobs, chunksize=2))


def summary(rows: list[dict]) -> str:
    """The study's figures in words."""
    held = [r for r in rows if r["held"]]
    accepted = [r for r in rows if r["check_accepts"]]
    bad = [r for r in accepted if not r["held"]]
    lines = [f"{len(rows)} plants: {len(held)} hold in simulation; the sampled check accepts "
             f"{len(accepted)} ({len([r for r in accepted if r['held']])} of the "
             f"{len(held)} that hold, {100 * len(accepted) / max(len(held), 1):.1f} %), "
             f"of which {len(bad)} fail"]
    for case in CASES:
        sub = [r for r in rows if r["case"] == case]
        lines.append(f"  {case}: {sum(r['held'] for r in sub)}/{len(sub)} hold, check "
                     f"accepts {sum(r['check_accepts'] for r in sub)}")
    if rows and all("class_counterexample" in r for r in rows):
        open_ = [r for r in held if r["class_counterexample"] is None]
        replayed = sum(bool(r["class_counterexample"] and r["class_counterexample"].get(
            "replayed_on_c")) for r in held)
        unsound = [r for r in accepted if r["class_counterexample"] is not None]
        lines.append(
            f"classes: {len(held) - len(open_)} of the {len(held)} plants that hold have a "
            f"member of their own class that leaves the tube (no sound check may accept "
            f"them); the search finds none for {len(open_)}, of which the check accepts "
            f"{sum(r['check_accepts'] for r in open_)}; accepted classes with a "
            f"counterexample: {len(unsound)}; counterexamples confirmed by the generated C "
            f"controller: {replayed} of {len(held) - len(open_)}")
        for case in CASES:
            sub = [r for r in held if r["case"] == case]
            lines.append(f"  {case}: {sum(r['class_counterexample'] is None for r in sub)} "
                         f"of {len(sub)} that hold without a counterexample found")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m stt_codegen.bench.plants_study",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="?", type=int, default=100,
                        help="plants per bundled case (default 100)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default=None, help="write every row as JSON")
    parser.add_argument("--classes", action="store_true",
                        help="also search each plant's class for a member that leaves the tube")
    parser.add_argument("--own-gain", action="store_true",
                        help="use the gain derived from each plant's own bounds instead of "
                             "the bundled design's")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    rows = study_plants(args.runs, args.workers, args.classes, args.own_gain)
    print(summary(rows))
    print(f"({time.perf_counter() - started:.0f} s)")
    if args.out:
        Path(args.out).write_text(json.dumps(rows, indent=1))
    unsound = any(r["check_accepts"] and (not r["held"] or r.get("class_counterexample"))
                  for r in rows)
    return 1 if unsound else 0


if __name__ == "__main__":
    sys.exit(main())
