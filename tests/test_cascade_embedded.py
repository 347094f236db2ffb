"""The cascade controller in closed loop on the emulated Cortex-M4F."""

from __future__ import annotations

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.embedded.cascade_loop import MEASURED_STEPS, run_cascade_embedded


@pytest.mark.embedded
@pytest.mark.parametrize("case", ["second-order-s1", "second-order-quadrotor"])
def test_cascade_on_the_cortex_m4f_is_satisfied_like_the_host(case) -> None:
    design = stt.design_tube(stt.load_spec(case))
    report = run_cascade_embedded(design)
    assert report["satisfied"], report
    assert report["outside_position"] == report["outside_velocity"] == report["invalid"] == 0
    assert len(report["instructions_per_step"]) == MEASURED_STEPS + 1
    assert all(1000 < c < 20000 for c in report["instructions_per_step"])
    host = stt.simulate(design, backend="c")       # double controller, same plant
    assert abs(report["reach_time"] - host.reach_time) <= 0.01
    assert abs(report["min_clearance"] - host.min_obstacle_clearance) <= 1e-3
    np.testing.assert_allclose(report["final_state"], host.trajectory.x[-1], atol=1e-3)
