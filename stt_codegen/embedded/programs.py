"""Test programs around a generated controller: the closed loop and the input replay.

Both are rendered from Jinja2 templates (``templates/embedded_closed_loop.c.j2``,
``templates/embedded_replay.c.j2``) and talk to the host in IEEE-754 bit patterns
(hex), so that nothing is lost in printing.

* :func:`closed_loop_source`: the controller step at ``rate_hz`` against the spec's plant
  (omnidirectional eq. (14) or single integrator), integrated in double by RK4 with
  :data:`stt_codegen.runtime.simulate.SUBSTEPS` substeps per period, with the disturbance of
  :class:`stt_codegen.runtime.plants.Disturbance` (same seed, same sinusoids), judged like
  :func:`stt_codegen.runtime.simulate.simulate`.
* :func:`replay_source`: ``P_step`` and ``P_tube`` at given float inputs; outputs printed
  as bits. Optionally each step is a measured region (instruction count, painted stack)
  or the floating-point exception flags of each call are printed (host builds).
"""

from __future__ import annotations

import math
import re
from dataclasses import asdict, dataclass

import numpy as np

from ..codegen.emit import c_source
from ..codegen.render import c_identifier, render
from ..runtime.dynamics import plant_function
from ..runtime.state_split import positions
from ..runtime.plants import Disturbance
from ..runtime.simulate import SUBSTEPS
from ..runtime.tasks import judge_tasks, until_met
from ..spec.loader import Spec
from ..spec.variants import variant_of
from ..tube.parameters import TubeDesign

__all__ = ["ClosedLoopOutput", "c_double", "closed_loop_source", "judge_printed", "loop_context",
           "parse_closed_loop", "parse_replay", "replay_source", "steps_of"]


def c_double(value: float) -> str:
    """A C double literal that reads back exactly (``HUGE_VAL`` for ``+inf``: a bound not
    given).

    Parameters
    ----------
    value : float
        A finite number, or ``+inf``.

    Returns
    -------
    str
        ``repr`` of the double (with a ``.0`` where it has no point or exponent).

    Raises
    ------
    ValueError
        ``value`` is NaN or ``-inf``.
    """
    if math.isinf(value) and value > 0:
        return "HUGE_VAL"
    text = repr(float(value))
    if not math.isfinite(float(value)):
        raise ValueError(f"non-finite constant {value!r}")
    return text if ("." in text or "e" in text) else text + ".0"


def steps_of(spec: Spec, design: TubeDesign) -> int:
    """Controller periods over ``[0, t_c]``, as :func:`stt_codegen.runtime.simulate.simulate`
    counts.

    Parameters
    ----------
    spec : Spec
        Gives ``t_c`` (s).
    design : TubeDesign
        Gives ``rate_hz`` (Hz).

    Returns
    -------
    int
        ``ceil(t_c * rate_hz)``.
    """
    return int(math.ceil(spec.prescribed_time * design.rate_hz - 1e-9))


def _obstacles(spec: Spec) -> list[dict]:
    out = []
    for u in spec.unsafe_sets:
        dims = list(u.dims)
        if u.kind == "box":
            faces = [(d, c_double(lo), c_double(hi)) for d, lo, hi in zip(dims, u.shape.lower, u.shape.upper)]
            out.append({"kind": "box", "dims": dims, "faces": faces})
        elif u.kind == "ball":
            out.append({"kind": "ball", "dims": dims,
                        "center": [(d, c_double(c)) for d, c in zip(dims, u.shape.center)],
                        "radius": c_double(u.shape.radius)})
        else:
            a_rows, b_vals = u.shape.halfspaces
            facets = [([(d, c_double(a)) for d, a in zip(dims, row)], c_double(b))
                      for row, b in zip(a_rows, b_vals)]
            out.append({"kind": "polytope", "dims": dims, "facets": facets})
    return out


def loop_context(spec: Spec, design: TubeDesign, *, seed: int = 0, decimate: int = 10,
                 replay: list[int] = ()) -> dict:
    """What the closed-loop templates of both orders share (``templates/_embedded_plant.j2``,
    ``_embedded_rk4.j2``, ``_embedded_judge.j2``): the names, the periods, the sets, the
    disturbance and the obstacles, as C literals.

    Parameters
    ----------
    spec, design
        The spec (sets, ``t_c``, disturbance) and its design (rate).
    seed : int
        Disturbance seed (as ``simulate(..., seed=seed)``).
    decimate : int
        Print the state every ``decimate`` steps (and at the last one).
    replay : list of int
        Steps whose controller inputs are printed, increasing.

    Returns
    -------
    dict
        Template variables.
    """
    prefix = c_identifier(spec.c_name)
    n = spec.dimension
    dist = Disturbance(n, spec.disturbance_amplitude, seed)
    return dict(
        P=prefix, U=prefix.upper(), spec_name=spec.name, real="float", n=n,
        steps=steps_of(spec, design), substeps=SUBSTEPS, decimate=int(decimate),
        terms=dist.weights.shape[1], seed=int(seed), rate_hz=f"{design.rate_hz:g}",
        rate_hz_d=c_double(design.rate_hz), t_c=c_double(spec.prescribed_time),
        has_delay=spec.delay > 0.0, delay=c_double(spec.delay),
        predict=bool(spec.compensate_delay),
        ss_lo=[c_double(v) for v in spec.state_space.lower], ss_hi=[c_double(v) for v in spec.state_space.upper],
        tg_lo=[c_double(v) for v in spec.target_set.lower], tg_hi=[c_double(v) for v in spec.target_set.upper],
        w_amp=c_double(dist.amplitude), w_c=[[c_double(v) for v in r] for r in dist.weights],
        w_omega=[[c_double(v) for v in r] for r in dist.frequencies],
        w_phi=[[c_double(v) for v in r] for r in dist.phases],
        replay=[int(k) for k in replay], obstacles=_obstacles(spec),
        has_obstacles=bool(spec.unsafe_sets))


def closed_loop_source(spec: Spec, design: TubeDesign, *, seed: int = 0, decimate: int = 10,
                       replay: list[int] = ()) -> str:
    """The closed-loop C program (see the template's header comment).

    Parameters
    ----------
    spec, design
        The spec (sets, ``t_c``, plant, disturbance) and its design (rate).
    seed : int
        Disturbance seed (as ``simulate(..., seed=seed)``).
    decimate : int
        Print the state every ``decimate`` steps (and at the last one).
    replay : list of int
        Steps whose controller inputs are printed (``S`` lines), increasing.

    Returns
    -------
    str
        The C source of the program (single precision), which prints the sampled states
        (``X`` lines), the replay steps' inputs (``S`` lines) and a ``closed loop:`` summary.
    """
    n = spec.dimension
    plant_doc = {"omnidirectional": "x_dot = R(x3) u + w, R the rotation by the heading x3 "
                                    "(eq. (14))",
                 "linear": "x_dot = a x + c + g u + w, the spec's matrices"}.get(
                     spec.plant_model, "x_dot = u + w")
    return render(
        "embedded_closed_loop.c.j2",
        **loop_context(spec, design, seed=seed, decimate=decimate, replay=replay),
        plant=spec.plant_model, plant_doc=plant_doc,
        x0=[c_double(v) for v in spec.initial_state],
        plant_rhs=c_source(plant_function(spec.plant_model, n, spec.linear_plant)).strip())


def float_bits(values) -> list[str]:
    """float32 bit patterns of ``values`` as C literals ``0x...u``."""
    a = np.asarray(values, dtype=np.float32).ravel()
    return [f"0x{int(b):08x}u" for b in a.view(np.uint32)]


def replay_source(spec: Spec, design: TubeDesign, x, t, dt, alpha, what: str,
                  prefix: str | None = None) -> str:
    """The replay program at float inputs ``x`` (N, n), ``t`` (N,), ``dt`` (N,), ``alpha`` (N, 2n).

    Every variant's step has the same signature; ``x`` is its measured state (the
    cascade's ``[x1; x2]``, a base's ``(x, y, theta)``).

    Parameters
    ----------
    spec : Spec
        Gives the generated code's prefix and the dimension ``n``.
    design : TubeDesign
        The design (the inputs are the program's data; the controller is the generated
        code it is linked with).
    x : array_like, shape (N, n)
        States, state units, rounded to float32.
    t : array_like, shape (N,)
        Times, s.
    dt : array_like, shape (N,)
        Sampling periods, s.
    alpha : array_like, shape (N, 2n)
        The adaptive law's ``alpha``.
    what : str
        What the inputs are, for the program's header comment.
    prefix : str, optional
        The controller's C prefix (default: the spec's C name).

    Returns
    -------
    str
        The C source of the program, which prints one ``R`` line per input.
    """
    prefix = c_identifier(spec.c_name) if prefix is None else prefix
    x = np.atleast_2d(np.asarray(x, dtype=np.float32))
    rows = [float_bits(np.concatenate([x[k], [t[k], dt[k]], alpha[k]])) for k in range(len(t))]
    return render("embedded_replay.c.j2", P=prefix, spec_name=spec.name, real="float",
                  n=spec.dimension, nx=x.shape[1], count=len(rows), rows=rows, what=what,
                  **variant_of(spec).replay_context)


def _f32(word: str) -> float:
    return float(np.array([int(word, 16)], dtype=np.uint32).view(np.float32)[0])


def _f64(word: str) -> float:
    return float(np.array([int(word, 16)], dtype=np.uint64).view(np.float64)[0])


@dataclass
class ReplayOutput:
    """Outputs of the replay program: ``status`` (N,), ``u`` (N, n), ``alpha_next`` (N, 2n),
    ``gamma_L``, ``gamma_U`` (N, n), ``stack`` (N,) painted bytes or ``None``,
    ``flags`` (N, 2) exception flags (step, tube) or ``None``, ``nonfinite`` (N,) bool."""

    status: np.ndarray
    u: np.ndarray
    alpha_next: np.ndarray
    gamma_L: np.ndarray
    gamma_U: np.ndarray
    stack: np.ndarray | None
    flags: np.ndarray | None
    nonfinite: np.ndarray | None


def parse_replay(stdout: str, n: int) -> ReplayOutput:
    """Parse the ``R`` (and ``F``) lines of the replay program.

    Parameters
    ----------
    stdout : str
        The program's standard output.
    n : int
        State dimension.

    Returns
    -------
    ReplayOutput
        One row per ``R`` line, in order.
    """
    rows, stacks, flags, nonfinite = [], [], [], []
    for line in stdout.splitlines():
        parts = line.split()
        if parts and parts[0] == "R":
            vals = [_f32(w) for w in parts[3:3 + 5 * n]]
            rows.append([int(parts[2])] + vals)
            if "stack" in parts:
                stacks.append(int(parts[parts.index("stack") + 1]))
        elif parts and parts[0] == "F":
            flags.append((int(parts[2]), int(parts[3])))
            nonfinite.append("nonfinite" in parts)
    a = np.array(rows, dtype=float).reshape(-1, 1 + 5 * n)
    return ReplayOutput(
        status=a[:, 0].astype(int), u=a[:, 1:1 + n], alpha_next=a[:, 1 + n:1 + 3 * n],
        gamma_L=a[:, 1 + 3 * n:1 + 4 * n], gamma_U=a[:, 1 + 4 * n:1 + 5 * n],
        stack=np.array(stacks) if stacks else None,
        flags=np.array(flags).reshape(-1, 2) if flags else None,
        nonfinite=np.array(nonfinite) if flags else None)


_SUMMARY = re.compile(r"^closed loop: (.*)$", re.MULTILINE)


@dataclass
class ClosedLoopOutput:
    """What the closed-loop program printed.

    Attributes
    ----------
    summary : dict
        The ``closed loop:`` line's fields (numbers; ``max_abs_u`` a list).
    states : dict of int to ndarray
        The printed plant states, by step.
    replay_inputs : dict of int to tuple
        The controller's inputs ``(t, alpha, x)`` at the replay steps, by step.
    """

    summary: dict
    states: dict
    replay_inputs: dict


def parse_closed_loop(stdout: str, n: int, state_size: int | None = None) -> ClosedLoopOutput:
    """Parse the closed-loop program's output (raises ``ValueError`` without a summary).

    Parameters
    ----------
    stdout : str
        The program's standard output.
    n : int
        State dimension (positions; ``alpha`` has ``2 n`` entries).
    state_size : int, optional
        Entries of the plant's state in the ``X`` and ``S`` lines (default ``n``; ``2 n``
        for a second-order plant's ``[x1; x2]``).

    Returns
    -------
    ClosedLoopOutput
        The summary, the states (state units) and the replay inputs.

    Raises
    ------
    ValueError
        No ``closed loop:`` summary line.
    """
    m = _SUMMARY.search(stdout)
    if m is None:
        raise ValueError("no 'closed loop:' summary line in the program's output")
    summary: dict = {}
    for item in m.group(1).split():
        key, value = item.split("=", 1)
        if key == "max_abs_u":
            summary[key] = [float(v) for v in value.split(",")]
        elif re.fullmatch(r"-?\d+", value):
            summary[key] = int(value)
        else:
            summary[key] = float(value)
    size = n if state_size is None else state_size
    states, replay = {}, {}
    for line in stdout.splitlines():
        parts = line.split()
        if parts and parts[0] == "X":
            states[int(parts[1])] = np.array([_f64(w) for w in parts[2:2 + size]])
        elif parts and parts[0] == "S":
            vals = [_f32(w) for w in parts[2:]]
            replay[int(parts[1])] = (vals[0], np.array(vals[1:1 + 2 * n]),
                                     np.array(vals[1 + 2 * n:1 + 2 * n + size]))
    return ClosedLoopOutput(summary, states, replay)


def judge_printed(spec: Spec, states: dict, rate_hz: float) -> dict:
    """The tasks and the moving obstacles judged on the states a closed-loop program printed
    (every ``decimate``-th step and the last), for both plant orders: what the program
    itself does not judge (it judges the static obstacles, the state space and the target
    at every step).

    The judgement is at the printed steps only, coarser than ``simulate``'s, which judges
    at every integration point: a task met, or an obstacle met, only between two printed
    steps is not seen.

    Parameters
    ----------
    spec : Spec
        Its ``tasks`` (:func:`~stt_codegen.runtime.tasks.judge_tasks`) and
        ``moving_obstacles`` (an obstacle until a task ends when the printed run meets it,
        :func:`~stt_codegen.runtime.tasks.until_met`).
    states : dict of int to ndarray
        Step index to the printed plant state (shape (n,), (2 n,) or a base's 3), whose
        positions :func:`~stt_codegen.runtime.state_split.positions` gives.
    rate_hz : float
        The controller's rate, Hz (a step's time is its index over it).

    Returns
    -------
    dict
        ``tasks`` (one dict per task, :class:`~stt_codegen.runtime.tasks.TaskOutcome`'s
        fields; with tasks only), ``moving_clearance`` (the least signed clearance from the
        moving obstacles, state units; with moving obstacles only) and ``met`` (every task
        met and every moving obstacle missed at the printed steps).
    """
    ks = sorted(states)
    t = np.array(ks, dtype=float) / rate_hz
    x = positions(spec, np.array([states[k] for k in ks]))
    outcomes = judge_tasks(spec, t, x)
    out: dict = {"met": all(o.met for o in outcomes)}
    if spec.tasks:
        out["tasks"] = [asdict(o) for o in outcomes]
    if spec.moving_obstacles:
        clearance = min(float(ob.signed_clearance(x, t).min())
                        for ob in until_met(spec, outcomes))
        out["moving_clearance"] = clearance if math.isfinite(clearance) else None
        out["met"] = out["met"] and clearance > 0.0
    return out

