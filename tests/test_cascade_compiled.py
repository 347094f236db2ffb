"""The sampled cascade's certificate with its per-sample step compiled (CasADi's virtual
machine, stt_codegen/design/certificate/cascade_step.py) against the plain-float loop it
replaced (tests/cascade_oracle.py, the code of 6fb655a): the same verdicts, reasons,
margins, peaks and times, float for float, on random stages, plant classes, delays and
jitters; each per-interval formula on ``SX`` symbols against its float original; the
enclosure grown row by row against the whole one (docs/second-order.md, "How the
certificate is evaluated")."""

from __future__ import annotations

import dataclasses
import pathlib

import casadi
import cascade_oracle as oracle
import numpy as np
import pytest
from conftest import design_of

import stt_codegen as stt
from stt_codegen.design.cascade_gain import derived_second_stage
from stt_codegen.design.certificate import certify_tube, enclose_tube
from stt_codegen.design.certificate.cascade_bounds import (step_velocity_change,
                                                           virtual_velocity_change)
from stt_codegen.design.certificate.cascade_sampled import (CascadeClass,
                                                            check_cascade_sampled)
from stt_codegen.design.certificate.growing import GrowingEnclosure
from stt_codegen.design.certificate.operations import SYMBOLS, exact_symbols
from stt_codegen.design.failures import without_advice
from stt_codegen.design.certificate.sampled_axis import (axis_interval, coupling_push,
                                                         peak_scalar, phi_scalar,
                                                         phi_slope_scalar)
from stt_codegen.design.samples import sample_tube
from stt_codegen.errors import DesignError
from stt_codegen.tube import reference

SPECS = pathlib.Path(__file__).parent / "specs"


def _tube(name: str, rate_hz: float):
    """``(spec, tube, samples, min_width)`` of a spec's position tube at ``rate_hz`` (the
    tube its cascade design certifies or refuses)."""
    spec = dataclasses.replace(stt.load_spec(str(SPECS / name)), rate_hz=rate_hz,
                               input_bound=None)
    try:
        with without_advice():                  # the tube only, no search for a rate
            tube = stt.design_tube(spec).tube
    except DesignError as error:
        tube = error.tried
    with reference.numpy_math():
        samples = sample_tube(tube)
    return spec, tube, samples, certify_tube(tube, spec).min_width


def _random_case(rng: np.random.Generator, spec, tube, min_width: float):
    """A random second stage (a shape of the design's family), plant class, initial
    velocity and timing."""
    n = tube.dimension
    g_min = float(rng.uniform(0.3, 1.5))
    g_max = g_min * float(rng.choice([1.0, rng.uniform(1.0, 4.0)]))
    coupling = float(rng.choice([0.0, rng.uniform(0.0, 0.5 * (g_max - g_min))]))
    drift, slope = float(rng.uniform(0.0, 1.0)), float(rng.choice([0.0, rng.uniform(0, 2)]))
    velocity = None if rng.random() < 0.3 else tuple(rng.uniform(0.3, 3.0, n).tolist())
    # one drift bound on every axis, or one per axis (the largest the stage's)
    per_axis = tuple((drift * rng.uniform(0.0, 1.0, n)).tolist()) if rng.random() < 0.5 else None
    plants = CascadeClass(g_min, g_max, coupling, per_axis or drift, slope,
                          float(rng.choice([0.0, 0.1, 3.0])) * float(rng.random()), velocity)
    shape = (float(rng.uniform(0.2, 1.5)), float(rng.uniform(3.0, 20.0)),
             float(np.exp(rng.uniform(np.log(0.3), np.log(30.0)))))
    start = rng.uniform(-0.2, 0.2, n).tolist()
    stage, _ = derived_second_stage(tube, min_width, (g_min, g_max),
                                    max(plants.drift_bounds(n)) + plants.disturbance_bound,
                                    start, shape)
    h = 1.0 / tube.rate_hz
    timing = [{}, {"delay": float(rng.uniform(0, 0.5)) * h},
              {"jitter": float(rng.uniform(0, 0.2)) * h},
              {"delay": float(rng.uniform(0, 0.4)) * h, "jitter": float(rng.uniform(0, 0.2)) * h},
              {"delay": float(rng.uniform(0.05, 1.0)) * h, "compensate": True}]
    return stage, plants, start, timing[int(rng.integers(len(timing)))]


def _fixed_cases(tube, min_width: float) -> list:
    """Two cases that fail otherwise than most random ones: a disturbance that throws the
    position out of its tube, an initial velocity beyond the velocity tube's clamp."""
    n = tube.dimension
    loud = CascadeClass(1.0, 1.0, 0.0, 0.0, 0.0, 200.0, None)
    quiet = CascadeClass(1.0, 1.0, 0.0, 0.0, 0.0, 0.0, None)
    stage, _ = derived_second_stage(tube, min_width, (1.0, 1.0), 200.0, [0.0] * n)
    still, _ = derived_second_stage(tube, min_width, (1.0, 1.0), 0.0, [0.0] * n)
    return [(stage, loud, [0.0] * n, {}), (still, quiet, [3.0] + [0.0] * (n - 1), {})]


def _same_checks(cases: int, seed: int, tubes, fixed: bool = False) -> list:
    """Both certificates on ``cases`` random cases per tube (and :func:`_fixed_cases`);
    returns the outcomes."""
    rng = np.random.default_rng(seed)
    seen = []
    for spec, tube, samples, min_width in tubes:
        growing = GrowingEnclosure(tube, samples)
        drawn = [_random_case(rng, spec, tube, min_width) for _ in range(cases)]
        for stage, plants, start, timing in drawn + (_fixed_cases(tube, min_width)
                                                     if fixed else []):
            with reference.numpy_math():          # the enclosures as the check's
                old = oracle.check_cascade_sampled(tube, samples, stage, plants, start,
                                                   **timing)
            new = check_cascade_sampled(tube, samples, stage, plants, start, **timing)
            shared = check_cascade_sampled(tube, samples, stage, plants, start, **timing,
                                           enclosure=growing)
            assert new == old, (timing, old.reason, new.reason)
            assert new.data == old.data and shared == old and shared.data == old.data
            seen.append((old.passed, old.reason.split(" may ")[0][:20], bool(timing)))
    return seen


def test_the_compiled_check_is_the_plain_loop_float_for_float():
    # at 100 Hz the U-maze's stages fail within a few hundred samples: quick, and for
    # several reasons, with and without timing (the slow test below passes too)
    design = design_of("pointmaze-umaze")              # its position tube, at 100 Hz
    with reference.numpy_math():
        samples = sample_tube(design.tube)
    seen = _same_checks(6, 0, [(design.spec, design.tube, samples, design.check.min_width)],
                        fixed=True)
    assert len({reason for _, reason, _ in seen}) >= 3
    assert {timed for _, _, timed in seen} == {True, False}


@pytest.mark.slow
def test_the_compiled_check_is_the_plain_loop_on_many_cases():
    tubes = [_tube("umaze-cascade.toml", 300.0), _tube("umaze-cascade.toml", 1000.0),
             _tube("hovercraft.toml", 650.0), _tube("medium-cascade.toml", 300.0)]
    spec = stt.load_spec("second-order-quadrotor")                # three axes, coupled
    tube = stt.design_tube(spec).tube
    with reference.numpy_math():
        samples = sample_tube(tube)
    tubes.append((spec, tube, samples, certify_tube(tube, spec).min_width))
    seen = _same_checks(10, 1, tubes, fixed=True)
    assert {passed for passed, _, _ in seen} == {True, False}
    assert len({reason for _, reason, _ in seen}) >= 3


def _symbolic(function, count: int, **keywords):
    """``function`` built on ``count`` SX symbols with ``ops=SYMBOLS``, mapped over columns."""
    with exact_symbols():
        xs = [casadi.SX.sym(f"x{j}") for j in range(count)]
        out = function(*xs, ops=SYMBOLS, **keywords)
        out = list(out) if isinstance(out, tuple) else [out]
        built = casadi.Function("f", xs, casadi.cse(out))

    def run(*columns):
        out = built.map(len(columns[0]))(*(np.asarray(c, dtype=float)[None, :]
                                           for c in columns))
        return [np.asarray(v).ravel() for v in (out if isinstance(out, tuple) else (out,))]

    return run


def _equal(new, old) -> bool:
    new, old = np.asarray(new, dtype=float), np.asarray(old, dtype=float)
    return bool(np.all((new == old) | (np.isnan(new) & np.isnan(old))))


def test_each_formula_on_symbols_is_its_float_original():
    rng = np.random.default_rng(2)
    m = 4000
    s = rng.uniform(-0.999, 0.999, m)
    assert _equal(_symbolic(phi_scalar, 1)(s)[0], [oracle.phi_scalar(v) for v in s])
    wide = np.concatenate([s, rng.uniform(-2, 2, 200), [1.0, -1.0]])
    assert _equal(_symbolic(phi_slope_scalar, 1)(wide)[0],
                  [oracle.phi_slope_scalar(v) for v in wide])
    ratio = np.concatenate([rng.uniform(0.0, 4.0, 300), np.exp(rng.uniform(0, 12, 300))])
    assert _equal(_symbolic(peak_scalar, 1)(ratio)[0], [oracle.peak_scalar(v) for v in ratio])
    # on floats its loop is written out (no call per halving): the same doubles
    edges = [2.0, np.nextafter(2.0, 3.0), 2.0 + 1e-9, 1e300, np.inf, np.nan, -1.0, 0.0]
    floats = np.concatenate([ratio, 2.0 + rng.uniform(0, 1e-6, 300), edges])
    assert _equal([peak_scalar(float(v)) for v in floats],
                  [oracle.peak_scalar(float(v)) for v in floats])
    cp = [rng.choice([0.0, 1.0]) * rng.uniform(0, 1, m), rng.uniform(0, 1, m),
          rng.uniform(0, 2, m), rng.choice([0.0, 0.3], m), rng.uniform(0, 1, m)]
    assert _equal(_symbolic(coupling_push, 5)(*cp)[0],
                  [oracle.coupling_push(*row) for row in zip(*cp)])
    # boxes [a, b] inside (-1, 1) of either sign, tube figures, gains, pushes
    a = rng.uniform(-0.95, 0.9, m)
    b = np.minimum(a + rng.choice([0.0, 1.0], m) * rng.uniform(0, 0.6, m), 0.95)
    g_min = rng.uniform(0.3, 1.0, m)
    g_max = g_min * rng.uniform(1.0, 3.0, m)
    box = [a, b, rng.uniform(-1, 1, m), rng.uniform(0.1, 1, m), rng.uniform(0, 0.3, m),
           g_min, g_max, rng.uniform(0, 0.9, m), rng.uniform(0, 0.01, m),
           rng.choice([0.0, 1.0], m) * rng.uniform(0, 0.01, m),
           rng.uniform(0, 0.5, m), rng.choice([0.0, 0.2], m)]
    news = _symbolic(axis_interval, 12)(*box)
    olds = np.array([oracle.axis_interval(*row) for row in zip(*box)]).T
    assert all(_equal(new, old) for new, old in zip(news, olds))
    reach = np.maximum(np.maximum(-a, b), rng.uniform(0, 0.99, m))
    step = [rng.uniform(0.01, 2, m), rng.uniform(1e-4, 1e-2, m), a, b,
            rng.uniform(-0.05, 0.05, m), rng.uniform(0.9, 1.1, m), reach,
            rng.uniform(0.1, 1, m), rng.uniform(0.1, 1, m), rng.uniform(0, 1e-3, m)]
    assert _equal(_symbolic(step_velocity_change, 10)(*step)[0],
                  [oracle.step_velocity_change(*row) for row in zip(*step)])
    assert _equal([step_velocity_change(*row) for row in zip(*step)],
                  [oracle.step_velocity_change(*row) for row in zip(*step)])
    path = rng.uniform(0, 1.0, m)
    virtual = [rng.uniform(0.01, 2, m), rng.uniform(1e-4, 1e-2, m), np.abs(a),
               np.maximum(path, np.abs(a)), rng.uniform(0, 3, m), rng.uniform(0, 1e-2, m),
               rng.uniform(0.1, 1, m), rng.uniform(1.0, 1.5, m)]
    assert _equal(_symbolic(virtual_velocity_change, 8)(*virtual)[0],
                  [oracle.virtual_velocity_change(*row) for row in zip(*virtual)])


def test_the_grown_enclosure_is_the_whole_ones_rows():
    tube = design_of("pointmaze-umaze").tube
    with reference.numpy_math():
        samples = sample_tube(tube)
    whole = enclose_tube(tube, samples)
    growing = GrowingEnclosure(tube, samples)
    for rows in (1, 7, 64, 65, 300, growing.count):
        part = growing.first(rows)
        for field in dataclasses.fields(whole):
            assert np.array_equal(getattr(part, field.name), getattr(whole, field.name)[:rows])


def test_an_input_limit_stops_the_check_where_the_full_check_passes_it():
    # the design's search without advice (certified_stage) stops a shape's check where its
    # input passes the bound: the same failure as the full check's peak says, never earlier
    # than the full check's figures put it, and a limit above the full peak changes nothing
    design = design_of("pointmaze-umaze")
    with reference.numpy_math():
        samples = sample_tube(design.tube)
    tube, n = design.tube, design.tube.dimension
    stage, _ = derived_second_stage(tube, design.check.min_width, (1.0, 1.0), 0.0, [0.0] * n)
    plants = CascadeClass(1.0, 1.0, 0.0, 0.0, 0.0, 0.0, None)
    full = check_cascade_sampled(tube, samples, stage, plants, [0.0] * n)
    above = check_cascade_sampled(tube, samples, stage, plants, [0.0] * n,
                                  input_limit=tuple(p * 1.01 + 1e-9 for p in full.peak_input))
    assert above == full and above.data == full.data
    axis = int(np.argmax(full.peak_input))
    limit = tuple(0.5 * p if i == axis else 10.0 * p + 1.0
                  for i, p in enumerate(full.peak_input))
    cut = check_cascade_sampled(tube, samples, stage, plants, [0.0] * n, input_limit=limit)
    assert not cut.passed and f"|u_{axis}| may reach" in cut.reason
    assert "beyond the input bound" in cut.reason
    assert limit[axis] < cut.peak_input[axis] <= full.peak_input[axis]
    assert cut.time <= full.peak_input_time[axis] + 1e-12
