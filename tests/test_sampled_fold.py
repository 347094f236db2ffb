"""Law (13)'s per-axis sampled check with its per-sample step folded into CasADi's virtual
machine (stt_codegen/design/certificate/sampled_fold.py) against the Python loop of
``check_sampled`` (``folded=False``, its oracle): the same verdicts, reasons, margins,
times, dimensions, bounds of ``|e|`` and report figures, float for float, on bundled
tubes with random plant classes (a differential drive's turning gains among them), gains,
rates, delays, jitters and stops; the formulas written for symbols against their float
originals (docs/sampled-data.md, "How the check is evaluated")."""

from __future__ import annotations

import dataclasses
import math
import pathlib

import casadi
import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.design.certificate.lyapunov import others_box, others_max
from stt_codegen.design.certificate.operations import SYMBOLS, exact_symbols
from stt_codegen.design.certificate.plant_class import plant_class
from stt_codegen.design.certificate.sampled import check_sampled
from stt_codegen.design.certificate.sampled_axis import held_speed, turned_gains
from stt_codegen.design.failures import without_advice
from stt_codegen.design.samples import sample_tube
from stt_codegen.spec.assumptions import Assumptions
from stt_codegen.tube import reference

SPECS = pathlib.Path(__file__).parent / "specs"


def _case(name: str):
    """``(spec, tube, samples)`` of a spec's design (without ``[actuator]``)."""
    spec = stt.load_spec(name if "-" in name and not name.endswith(".toml")
                         else str(SPECS / name))
    spec = dataclasses.replace(spec, input_bound=None)
    with without_advice():
        tube = stt.design_tube(spec).tube
    return spec, tube


def _same(a, b) -> None:
    """``a`` and ``b`` (two :class:`SampledCheck`) equal float for float."""
    assert (a.passed, a.reason, a.dimension) == (b.passed, b.reason, b.dimension)
    for name in ("level", "margin", "time"):
        x, y = getattr(a, name), getattr(b, name)
        assert x == y or (math.isnan(x) and math.isnan(y)), (name, x, y)
    assert (a.abs_e is None) == (b.abs_e is None)
    if a.abs_e is not None:
        assert a.abs_e.shape == b.abs_e.shape
        assert np.array_equal(a.abs_e, b.abs_e)
    # the signed box of e at each sample (where passed), of which abs_e is the magnitude
    assert (a.e_box is None) == (b.e_box is None)
    if a.e_box is not None:
        assert np.array_equal(a.e_box, b.e_box)
        assert np.array_equal(np.maximum(-a.e_box[..., 0], a.e_box[..., 1]), a.abs_e)
    assert a.data == b.data


def _random_class(rng: np.random.Generator, base: Assumptions, turn: bool) -> Assumptions:
    g_min = float(rng.uniform(0.3, 1.2))
    g_max = g_min * float(rng.choice([1.0, rng.uniform(1.0, 3.0)]))
    out = dataclasses.replace(
        base, input_gain=(g_min, g_max),
        input_gain_skew=float(rng.choice([0.0, rng.uniform(0.0, 0.3)])),
        input_gain_coupling=float(rng.choice([0.0, rng.uniform(0.0, 0.5)])),
        drift_bound=float(rng.choice([0.0, rng.uniform(0.0, 0.5)])),
        disturbance_bound=float(rng.uniform(0.0, 0.3)))
    if turn:
        out = dataclasses.replace(out, input_gain_turn=(float(rng.uniform(0.5, 10.0)),
                                                        float(rng.uniform(0.0, 1.0))))
    return out


# a differential drive (coupled, turning gains), a coupled omnidirectional robot, a diagonal
# one among moving obstacles
CASES = ("office-drive.toml", pytest.param("omnirobot-s1", marks=pytest.mark.slow),
         pytest.param("crossing-moving", marks=pytest.mark.slow))


@pytest.mark.parametrize("name", CASES)
def test_fold_equals_loop_on_random_classes(name: str) -> None:
    spec, tube = _case(name)
    rng = np.random.default_rng(sum(map(ord, name)))
    own = plant_class(spec)
    turn = own.assumptions.input_gain_turn is not None
    verdicts = set()
    starts = np.random.default_rng(7)          # the boxes' own draws: the others unchanged
    with reference.numpy_math():
        for j in range(8):
            rate = tube.rate_hz * float(rng.choice([0.25, 0.5, 1.0, 2.0]))
            design = dataclasses.replace(tube, rate_hz=rate,
                                         gain=tube.gain * float(rng.uniform(0.3, 3.0)))
            samples = sample_tube(design)
            plants = own if j == 0 else _random_class(rng, own.assumptions, turn)
            stop_at = int(rng.integers(1, len(samples.t))) if j % 3 == 2 else None
            stop = None if stop_at is None else (lambda k, e, at=stop_at: k >= at)
            dt = 1.0 / rate
            timing = [{}, {"delay": float(rng.uniform(0.0, 0.6)) * dt},
                      {"jitter": float(rng.uniform(0.0, 0.2)) * dt},
                      {"delay": float(rng.uniform(0.0, 0.4)) * dt,
                       "jitter": float(rng.uniform(0.0, 0.2)) * dt}][j % 4]
            # every other draw from a box of e(0) (a switch's, docs/sensing.md)
            if j % 2:
                timing["initial_error"] = [tuple(sorted(starts.uniform(-0.3, 0.3, 2)))
                                           for _ in range(design.dimension)]
            loop = check_sampled(design, samples, plants, lyapunov=False, stop=stop,
                                 folded=False, **timing)
            fold = check_sampled(design, samples, plants, lyapunov=False, stop=stop,
                                 **timing)
            _same(loop, fold)
            verdicts.add("stopped" if "stopped_at" in loop.data else
                         "passed" if loop.passed else loop.reason.split(" ")[0])
    # the draws reach a pass and a failure (the comparison is not of passes only)
    assert "passed" in verdicts and len(verdicts) >= 2, verdicts


# the Lyapunov form (about 5 s) in the slow tier; the other form keeps the test fast
@pytest.mark.parametrize("lyapunov", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_a_box_of_e0_bounds_every_start_in_it(lyapunov: bool) -> None:
    """The check from a box of ``e(0)`` holding ``e(x(0))`` proves bounds no smaller than the
    check from ``x(0)`` at every sample, and grows with the box; a box reaching the edge
    fails; a box that is not one interval per dimension inside (-1, 1) is refused."""
    spec, tube = _case("office-drive.toml")
    plants = plant_class(spec)
    with reference.numpy_math():
        samples = sample_tube(tube)
        point = check_sampled(tube, samples, plants, lyapunov=lyapunov)
        boxes = [check_sampled(tube, samples, plants, lyapunov=lyapunov,
                               initial_error=[(-w, w)] * tube.dimension)
                 for w in (0.05, 0.2, 0.4)]
        edge = check_sampled(tube, samples, plants, lyapunov=lyapunov,
                             initial_error=[(-0.999, 0.999)] * tube.dimension)
        for bad in ([(-0.1, 0.1)], [(0.2, 0.1)] * 2, [(-1.0, 0.1)] * 2):
            with pytest.raises(ValueError, match="initial_error"):
                check_sampled(tube, samples, plants, initial_error=bad)
    assert point.passed and all(b.passed for b in boxes)
    for wide, narrow in zip(boxes, [point] + boxes[:-1]):
        assert np.all(wide.abs_e >= narrow.abs_e) and wide.level >= narrow.level
    assert boxes[-1].abs_e[0].max() == pytest.approx(0.4)
    assert np.any(boxes[-1].abs_e > point.abs_e)
    assert not edge.passed


@pytest.mark.slow
def test_with_the_balls_the_loop_runs() -> None:
    """With the Lyapunov balls (a coupled block, no delay) the loop runs: the same result
    with ``folded`` either way; with a delay the balls are not used and the fold runs."""
    spec, tube = _case("omnirobot-s1")
    plants = plant_class(spec)
    dt = 1.0 / tube.rate_hz
    with reference.numpy_math():
        samples = sample_tube(tube)
        for kwargs in ({}, {"delay": 0.3 * dt}, {"jitter": 0.1 * dt}):
            _same(check_sampled(tube, samples, plants, folded=False, **kwargs),
                  check_sampled(tube, samples, plants, **kwargs))


def _symbolic(f, count: int):
    with exact_symbols():
        args = casadi.SX.sym("a", count)
        out = f(*[args[i] for i in range(count)])
        outs = out if isinstance(out, tuple) else (out,)
        return casadi.Function("f", [args], [casadi.vertcat(*outs)])


def test_new_symbolic_formulas_equal_their_floats() -> None:
    rng = np.random.default_rng(3)
    turned = _symbolic(lambda *a: turned_gains(*a, ops=SYMBOLS), 5)
    box = _symbolic(lambda a, b, h, k: others_box([a, b], [h, k], SYMBOLS), 4)
    held = _symbolic(lambda r0, r1, s0, s1, *g: held_speed(0, (0, 1), [r0, r1], [s0, s1], *g,
                                                           ops=SYMBOLS), 9)
    for _ in range(300):
        angle = float(rng.choice([rng.uniform(0.0, 0.3), rng.uniform(1.0, 3.0)]))
        gains = [angle, *rng.uniform(0.2, 2.0, 4).tolist()]
        assert np.asarray(turned(gains)).ravel().tolist() == list(turned_gains(*gains))
        limits, halves = rng.uniform(0.0, 3.0, 2).tolist(), rng.uniform(0.01, 2.0, 2).tolist()
        expected = others_max(limits, math.inf, halves)
        assert others_box(limits, halves) == expected
        assert float(box(limits + halves)) == expected
        args = [*rng.uniform(0.0, 0.9, 2).tolist(), *rng.uniform(0.0, 50.0, 2).tolist(),
                *rng.uniform(0.1, 2.0, 5).tolist()]
        assert float(held(args)) == held_speed(0, (0, 1), args[:2], args[2:4], *args[4:])
