"""The cascade controller in closed loop on the emulated Cortex-M4F."""

from __future__ import annotations

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.embedded.cascade_loop import run_cascade_embedded
from stt_codegen.embedded.deploy import COUNT_FRACTIONS


@pytest.mark.embedded
@pytest.mark.parametrize("case", ["second-order-s1", "second-order-quadrotor"])
def test_cascade_on_the_cortex_m4f_is_satisfied_like_the_host(case) -> None:
    design = stt.design_tube(stt.load_spec(case))
    report = run_cascade_embedded(design)
    assert report["satisfied"], report
    assert report["outside_position"] == report["outside_velocity"] == report["invalid"] == 0
    assert len(report["instructions_per_step"]) == len(COUNT_FRACTIONS)
    assert all(1000 < c < 20000 for c in report["instructions_per_step"])
    assert report["instructions_worst"] == max(report["instructions_per_step"])
    assert report["period_share_lower"] == pytest.approx(
        report["instructions_worst"] / 168e6 * design.spec.rate_hz)
    if case == "second-order-quadrotor":
        # the target (exact emulated counts, not time): at most 3000 on average;
        # no log or exp of these steps reaches newlib
        assert np.mean(report["instructions_per_step"]) <= 3000, report["instructions_per_step"]
        names = report["instructions_by_function"]
        assert not {"logf", "__ieee754_logf", "expf", "__ieee754_expf"} & set(names), names
    assert report["measured_times"][0] == 0.0
    assert report["measured_times"][-1] == pytest.approx(0.999 * design.spec.prescribed_time,
                                                         abs=2e-3)
    host = stt.simulate(design, backend="c")       # double controller, same plant
    assert abs(report["reach_time"] - host.reach_time) <= 0.01
    assert abs(report["min_clearance"] - host.min_obstacle_clearance) <= 1e-3
    np.testing.assert_allclose(report["final_state"], host.trajectory.x[-1], atol=1e-3)


def test_the_cascade_loop_is_a_template_sharing_the_first_orders_pieces() -> None:
    """The program is rendered from templates/cascade_closed_loop.c.j2 (no C text in the
    Python module), and its disturbance, RK4 step and obstacle judgement are the first-order
    program's text (the shared includes)."""
    import dataclasses
    import inspect
    import re

    from second_order_helpers import as_double_integrator, planar_s1

    from stt_codegen.embedded import cascade_loop
    from stt_codegen.embedded.programs import closed_loop_source

    source = inspect.getsource(cascade_loop)
    assert not re.search(r"#include|int main|printf|static (void|double|const)", source)
    spec, design, _ = planar_s1()
    second = dataclasses.replace(design, spec=as_double_integrator(spec, mass=1.3))
    program = cascade_loop.closed_loop_program(second, "planar_s1_cascade")
    first = closed_loop_source(spec, design.tube)

    def function(text: str, name: str) -> str:
        start = text.index(name)
        return text[start:text.index("\n}\n", start)]

    for name in ("static void disturbance(", "static void rk4(", "static double clearance(",
                 "static void print_state("):
        assert function(program, name) == function(first, name), name
    assert "#define NX (2 * N)" in program and "#define NX N" in first
    assert "static const double PARAMS[NPARAMS] = { 1.3 };" in program
    assert "planar_s1_cascade_step(xf, tf, dtf, alpha, uf, alpha_next)" in program
