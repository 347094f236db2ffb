"""The wide study of unknown plants: simulation against the sampled check.

Draws plants ``x_dot = f(x) + g(x) u + w`` over wide ranges (``|f|`` up to about 6,
eigenvalues of the symmetric part of ``g`` in ``[0.05, 5]``, a skew part up to 1,
``|w_i| <= 0.5``), runs the generated C controller of each bundled case (its design's gain
and rate) against each, and asks the sampled check
(:func:`~stt_codegen.design.certificate.sampled.check_sampled`) whether it proves that plant's own
bounds, without and with the plant's own Lipschitz bounds (:func:`own_bounds`). A plant
the check accepts must hold in simulation; the study reports how many of the plants that
hold the check accepts.

The plants and seeds are those of the former ``tests/study_unknown_dynamics.py`` (issue
7), which this module replaces, so that the numbers compare. Run::

    python -m stt_codegen_bench.plants_study [RUNS_PER_CASE] [--workers W] [--out rows.json]
                                             [--classes] [--own-gain]
    python -m stt_codegen_bench.plants_study --recheck rows.json [--out new.json]

``--classes`` also searches the class of each plant that holds for a member that leaves
the tube, with three adversaries (:data:`ADVERSARIES`): the switching one
(:func:`~stt_codegen.verification.class_search.search_class` on the plant's own bounds, ``g`` and
``f`` may jump), the Lipschitz one (the same search with the plant's own Lipschitz bounds
too) and the time-invariant one
(:func:`~stt_codegen.verification.class_search.search_time_invariant`, ``g`` and ``f`` constant).
No sound check may accept a class with such a member (a class with Lipschitz bounds: one
the Lipschitz or the time-invariant adversary found), so the study says how many of the
plants that hold any sound check could accept at most, and how many of those the check
accepts (:func:`summary`). The adversaries are the expensive part; ``--recheck`` computes
only the check's columns again, of a study saved with ``--out`` (which is written after
every plant, so a stopped run keeps its rows). ``--own-gain``
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

from stt_codegen.design.gain import derived_gain
from stt_codegen.design.samples import sample_tube
from stt_codegen.design.search import design_tube
from stt_codegen.runtime.simulate import run_closed_loop
from stt_codegen.spec.assumptions import Assumptions
from stt_codegen.spec.loader import load_spec
from stt_codegen.design.certificate.sampled import check_sampled
from stt_codegen.verification.class_search import replay, search_class, search_time_invariant, unit_skew

__all__ = ["ADVERSARIES", "CASES", "COLUMNS", "RANGES", "check_columns", "draw",
           "own_bounds", "plant_parameters", "recheck", "study_one", "study_plants", "summary",
           "table", "unsound"]

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


def own_bounds(p: dict, spec, lipschitz: bool = False) -> Assumptions:
    """The bounds a user who knew the drawn plant would declare (over the state space).

    With ``lipschitz``, also the plant's Lipschitz bounds, per state ``j`` (the
    ``[assumptions]`` keys ``input_gain_lipschitz`` and ``drift_lipschitz``):

    * ``g(x) - g(y) = skew (tanh(v.x) - tanh(v.y)) K`` and ``|tanh a - tanh b| <= |a - b|``
      (``tanh' = sech^2 <= 1``), so ``|g(x) - g(y)|_2 <= skew |K|_2 sum_j |v_j| |x_j -
      y_j|``: ``L_j = skew |v_j| |K|_2``;
    * ``f(x) - f(y) = int_0^1 J(y + s (x - y)) (x - y) ds`` with the Jacobian ``J(z) =
      f_amp diag(cos(W z + phi)) W + L``, whose column ``j`` has Euclidean norm at most
      ``f_amp |W[:, j]| + |L[:, j]|`` (``|cos| <= 1``): ``L_j`` that sum.

    Both hold on all of ``R^n``, not only on the state space.

    Parameters
    ----------
    p : dict
        The plant, from :func:`plant_parameters`.
    spec : Spec
        Gives the state space the drift is bounded over.
    lipschitz : bool, optional
        Also set ``input_gain_lipschitz`` and ``drift_lipschitz`` (default: ``None``, the
        class whose ``g`` and ``f`` may jump).

    Returns
    -------
    Assumptions
        ``input_gain`` (the extreme eigenvalues of ``S``), ``input_gain_skew``,
        ``input_gain_coupling``, ``drift_bound`` and ``disturbance_bound`` (Euclidean, over
        the state space); with ``lipschitz`` the two Lipschitz bounds, ``n`` values each
        (``g``'s in its units per state unit, ``f``'s per second).
    """
    n = spec.dimension
    eig = np.linalg.eigvalsh(p["sym"])
    k_mat = unit_skew(p["skew_axis"])
    off = p["sym"] - np.diag(np.diag(p["sym"]))
    coupling = float(np.max(np.linalg.norm(off, axis=1)
                            + p["skew"] * np.linalg.norm(k_mat, axis=1)))
    half = (np.array(spec.state_space.upper) - np.array(spec.state_space.lower)) / 2
    drift = p["f_amp"] * math.sqrt(n) + np.linalg.norm(p["L"], 2) * np.linalg.norm(half)
    rates = {}
    if lipschitz:
        rates = {"input_gain_lipschitz": tuple(
                     float(v) for v in p["skew"] * np.abs(p["v"]) * np.linalg.norm(k_mat, 2)),
                 "drift_lipschitz": tuple(
                     float(v) for v in p["f_amp"] * np.linalg.norm(p["W"], axis=0)
                     + np.linalg.norm(p["L"], axis=0))}
    return Assumptions((float(eig[0]), float(eig[-1])), float(p["skew"]), coupling,
                       float(drift), float(p["w_amp"] * math.sqrt(n)), **rates)


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


def _setup(case: str, index: int, own_gain: bool | float):
    """The design (at the plant's own gain when ``own_gain``; at that gain when a number),
    its samples, the plant and its bounds without and with Lipschitz bounds."""
    spec, design, samples = _designed(case)
    p = plant_parameters(draw(case, index))
    bounds = own_bounds(p, spec)
    if own_gain is True:
        design = dataclasses.replace(
            design, gain=derived_gain(_min_width(case), design.rate_hz, bounds))
    elif own_gain is not False:
        design = dataclasses.replace(design, gain=float(own_gain))
    return spec, design, samples, p, bounds, own_bounds(p, spec, lipschitz=True)


def check_columns(case: str, index: int, gain: float) -> dict:
    """The sampled check's verdicts on plant ``index``'s own class, without and with its
    Lipschitz bounds (:func:`~stt_codegen.design.certificate.sampled.check_sampled`), at ``gain``.

    Cheap beside the adversaries: :func:`recheck` recomputes these columns of a saved
    study.

    Parameters
    ----------
    case : str
        One of :data:`CASES`.
    index : int
        The plant's number within the case.
    gain : float
        ``k`` of law (13) (the row's ``gain``).

    Returns
    -------
    dict
        ``check_accepts``, ``check_s`` (s), ``check_fails_at`` (s or ``None``) for the
        class without Lipschitz bounds, and the same keys ending ``_lipschitz`` for the
        class with the plant's own.
    """
    _, design, samples, _, bounds, rated = _setup(case, index, gain)
    row = {}
    for suffix, b in (("", bounds), ("_lipschitz", rated)):
        started = time.perf_counter()
        verdict = check_sampled(design, samples, b)
        row[f"check_accepts{suffix}"] = bool(verdict.passed)
        row[f"check_s{suffix}"] = time.perf_counter() - started
        row[f"check_fails_at{suffix}"] = None if verdict.passed else float(verdict.time)
    return row


#: The adversaries of ``--classes``, by the row's key (docs/sampled-data.md, "The wide
#: study"): the switching one on the class that may jump, the Lipschitz one on the class
#: with the plant's own Lipschitz bounds, the time-invariant one (``g`` and ``f`` constant).
ADVERSARIES = ("switching", "lipschitz", "time_invariant")


def _adversaries(design, samples, bounds: Assumptions, rated: Assumptions) -> dict:
    """Each adversary's member that leaves the tube (figures, confirmed or not by the
    generated C controller, and the search's time), or ``None``."""
    out = {}
    for key, search in (("switching", lambda: search_class(design, samples, bounds)),
                        ("lipschitz", lambda: search_class(design, samples, rated)),
                        ("time_invariant", lambda: search_time_invariant(design, samples,
                                                                         bounds))):
        started = time.perf_counter()
        found = search()
        seconds = time.perf_counter() - started
        out[key] = None if found is None else {**found.to_json(),
                                               "replayed_on_c": replay(design, found)}
        out[f"{key}_s"] = seconds
    return out


def study_one(job: tuple) -> dict:
    """One plant: whether it holds in simulation, the check's verdicts on its own class
    (:func:`check_columns`), and, when it fails, whether it holds at 2, 4 or 8 times the
    rate.

    ``job`` is ``(case, index)``, ``(case, index, classes)`` or ``(case, index, classes,
    own_gain)``. With ``classes`` true, a plant that holds gets the members of its class
    that leave the tube found by each of :data:`ADVERSARIES` (the switching search of
    :func:`~stt_codegen.verification.class_search.search_class` on its own bounds; the same
    search on its bounds with its own Lipschitz bounds, :func:`own_bounds`; and
    :func:`~stt_codegen.verification.class_search.search_time_invariant`): each the
    :meth:`~stt_codegen.verification.class_search.Counterexample.to_json` figures and
    ``replayed_on_c``, or ``None`` when the search finds none, and the search's time
    (``<key>_s``). With ``own_gain`` true, the gain of law (13) is the one the design
    derives from the plant's own bounds (:func:`~stt_codegen.design.gain.derived_gain` at
    the design's certified narrowest width), as if the user had declared them in
    ``[assumptions]``, for the check, the searches and the simulation alike; otherwise it
    is the bundled design's (derived from the robot's bounds).

    Parameters
    ----------
    job : tuple
        ``(case, index[, classes[, own_gain]])``: a case of :data:`CASES`, the plant's index
        and two bools (default ``False``).

    Returns
    -------
    dict
        The knobs and ``held``, ``gain``, the plant's own bounds (``g_min_own``,
        ``g_max_own``, ``coupling``, ``push``, ``input_gain_lipschitz``,
        ``drift_lipschitz``), :func:`check_columns`; with ``classes`` and when it held, the
        keys of :data:`ADVERSARIES`; when it did not hold ``holds_at_rate_factor`` (2, 4,
        8 or ``None``).
    """
    case, index = job[:2]
    classes, own_gain = (tuple(job[2:]) + (False, False))[:2]
    _, design, samples, p, bounds, rated = _setup(case, index, bool(own_gain))
    gain = design.gain if own_gain else None
    held = _holds(case, p, gain=gain)
    row = {"case": case, "index": index, **draw(case, index), "held": held,
           "gain": design.gain, "g_min_own": bounds.input_gain[0],
           "g_max_own": bounds.input_gain[1], "coupling": bounds.input_gain_coupling,
           "push": bounds.drift_bound + bounds.disturbance_bound,
           "input_gain_lipschitz": list(rated.input_gain_lipschitz),
           "drift_lipschitz": list(rated.drift_lipschitz),
           **check_columns(case, index, design.gain)}
    if classes and held:
        row.update(_adversaries(design, samples, bounds, rated))
    if not held:
        row["holds_at_rate_factor"] = next(
            (f for f in (2.0, 4.0, 8.0) if _holds(case, p, f, gain)), None)
    return row


def _map(function, jobs: list, workers: int, done=None) -> list:
    """``function`` over ``jobs`` in order, in ``workers`` processes; ``done(results so
    far)`` after each."""
    results = []
    pool = ProcessPoolExecutor(workers) if workers > 1 else None
    try:
        for result in (pool.map(function, jobs, chunksize=1) if pool else map(function, jobs)):
            results.append(result)
            if done is not None:
                done(results)
    finally:
        if pool is not None:
            pool.shutdown()
    return results


def _in_order(rows: list[dict]) -> list[dict]:
    return sorted(rows, key=lambda r: (CASES.index(r["case"]), r["index"]))


def study_plants(runs: int, workers: int = 2, classes: bool = False,
                 own_gain: bool = False, done=None) -> list[dict]:
    """``runs`` plants per bundled case (:func:`study_one`, with the adversaries when
    ``classes``, at the gain derived from each plant's bounds when ``own_gain``), in
    parallel.

    The plants run index by index across the cases (plant 0 of each case, then plant 1,
    ...), so that the rows done when a run is stopped are the first plants of every case,
    the rows a shorter run gives (every plant is seeded by its case and index).

    Parameters
    ----------
    runs : int
        Plants per case.
    workers : int, optional
        Processes; 1 or fewer runs them in this process.
    classes : bool, optional
        Search each class that holds with the adversaries.
    own_gain : bool, optional
        Use the gain derived from each plant's own bounds.
    done : callable, optional
        Called with the rows so far after each plant (``main`` writes them).

    Returns
    -------
    list of dict
        :func:`study_one`'s rows, case by case, in index order.
    """
    jobs = [(case, i, classes, own_gain) for i in range(runs) for case in CASES]
    return _in_order(_map(study_one, jobs, workers, done))


def _recheck_one(row: dict) -> dict:
    return {**row, **check_columns(row["case"], row["index"], row["gain"])}


def recheck(rows: list[dict], workers: int = 2) -> list[dict]:
    """``rows`` with the check's columns (:func:`check_columns`) computed again, the
    simulation and the adversaries kept (for a study saved before the check changed).

    Parameters
    ----------
    rows : list of dict
        :func:`study_plants`'s rows (from ``--out``).
    workers : int, optional
        Processes; 1 or fewer runs them in this process.

    Returns
    -------
    list of dict
        The same rows, in the same order, with new check columns.
    """
    return _map(_recheck_one, rows, workers)


def _broken(row: dict, keys=ADVERSARIES) -> bool:
    return any(row.get(k) is not None for k in keys)


def unsound(rows: list[dict]) -> list[dict]:
    """The rows whose class the check accepts although it cannot be right: the plant does
    not hold, or an adversary of that class broke it (any of :data:`ADVERSARIES` for the
    class that may jump; the Lipschitz and time-invariant ones, whose members obey the
    plant's Lipschitz bounds, for the class with them). Must be empty.

    Parameters
    ----------
    rows : list of dict
        :func:`study_plants`'s rows.

    Returns
    -------
    list of dict
        The rows that contradict the check.
    """
    return [r for r in rows
            if (r["check_accepts"] and (not r["held"] or _broken(r)))
            or (r["check_accepts_lipschitz"]
                and (not r["held"] or _broken(r, ("lipschitz", "time_invariant"))))]


#: The columns of :func:`summary`'s table.
COLUMNS = ("plants", "hold", "broken: switching", "broken: Lipschitz",
           "broken: time-invariant", "broken by neither TI nor Lipschitz",
           "check accepts", "check accepts, Lipschitz",
           "of those unbroken, accepted with Lipschitz", "accepted but broken")


def table(rows: list[dict]) -> list[list[int]]:
    """:data:`COLUMNS` counted over all ``rows`` (first line) and per case; the classes
    broken and accepted are counted among the plants that hold ("accepted but broken":
    :func:`unsound`, over all plants).

    Parameters
    ----------
    rows : list of dict
        The study's rows (:func:`study_one`, with or without the adversaries).

    Returns
    -------
    list of list of int
        One line per group (all, then each case of :data:`CASES`), one count per column of
        :data:`COLUMNS`.
    """
    lines = []
    for case in (None,) + CASES:
        sub = [r for r in rows if case is None or r["case"] == case]
        held = [r for r in sub if r["held"]]
        open_ = [r for r in held if not _broken(r, ("lipschitz", "time_invariant"))]
        lines.append([len(sub), len(held),
                      sum(r.get("switching") is not None for r in held),
                      sum(r.get("lipschitz") is not None for r in held),
                      sum(r.get("time_invariant") is not None for r in held),
                      len(open_),
                      sum(r["check_accepts"] for r in held),
                      sum(r["check_accepts_lipschitz"] for r in held),
                      sum(r["check_accepts_lipschitz"] for r in open_),
                      len(unsound(sub))])
    return lines


def summary(rows: list[dict]) -> str:
    """The study's figures: a Markdown table (:data:`COLUMNS`, all and per case) when the
    rows have the adversaries, else the plants that hold and the check's verdicts.

    Parameters
    ----------
    rows : list of dict
        The study's rows (:func:`study_one`).

    Returns
    -------
    str
        The text printed by the command line, one line per group and, with the
        adversaries, how many of their members the generated C controller confirmed.
    """
    names = ("all",) + tuple(f"`{c}`" for c in CASES)
    if rows and all(k in r for r in rows if r["held"] for k in ADVERSARIES):
        lines = ["| | " + " | ".join(COLUMNS) + " |", "|---" * (len(COLUMNS) + 1) + "|"]
        lines += [f"| {name} | " + " | ".join(str(v) for v in counts) + " |"
                  for name, counts in zip(names, table(rows))]
        confirmed = {k: sum(bool(r.get(k) and r[k]["replayed_on_c"]) for r in rows)
                     for k in ADVERSARIES}
        found = {k: sum(r.get(k) is not None for r in rows) for k in ADVERSARIES}
        lines.append("members confirmed by the generated C controller: " + ", ".join(
            f"{k} {confirmed[k]} of {found[k]}" for k in ADVERSARIES))
        return "\n".join(lines)
    lines = []
    for name, counts in zip(names, table(rows)):
        lines.append(f"{name}: {counts[0]} plants, {counts[1]} hold; the check accepts "
                     f"{counts[6]} of those, {counts[7]} with their Lipschitz bounds; "
                     f"accepted but not holding: {counts[9]}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m stt_codegen_bench.plants_study",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="?", type=int, default=100,
                        help="plants per bundled case (default 100)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default=None, help="write every row as JSON")
    parser.add_argument("--classes", action="store_true",
                        help="also search each class that holds with the three adversaries")
    parser.add_argument("--own-gain", action="store_true",
                        help="use the gain derived from each plant's own bounds instead of "
                             "the bundled design's")
    parser.add_argument("--recheck", default=None, metavar="ROWS_JSON",
                        help="recompute only the check's columns of a saved study (written "
                             "back to --out, or to ROWS_JSON)")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    out = args.out or args.recheck

    def save(rows: list[dict]) -> None:        # after every plant: a stopped run keeps them
        if out:
            Path(out).write_text(json.dumps(_in_order(rows), indent=1))

    if args.recheck:
        rows = recheck(json.loads(Path(args.recheck).read_text()), args.workers)
    else:
        rows = study_plants(args.runs, args.workers, args.classes, args.own_gain, save)
    save(rows)
    print(summary(rows))
    print(f"({time.perf_counter() - started:.0f} s)")
    bad = unsound(rows)
    if bad:
        print("SOUNDNESS ALARM: the check accepts classes it cannot: " + ", ".join(
            f"{r['case']} #{r['index']}" for r in bad))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
