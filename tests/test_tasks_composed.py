"""Tasks that compose, all at once (tests/specs/tasks-composed.toml): three unordered tasks
in overlapping windows, an or-target, a moving obstacle and input bounds, designed,
certified, and met by the generated C on the host and on the Cortex-M4F."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import stt_codegen as stt

SPEC = Path(__file__).parent / "specs" / "tasks-composed.toml"


@pytest.fixture(scope="module")
def design():
    return stt.design_tube(stt.load_spec(SPEC))


def test_every_feature_is_in_the_spec_and_certified(design):
    spec = design.spec
    assert len(spec.tasks) == 3 and spec.task_order == "any"
    assert all(a.window[0] < b.window[1] and b.window[0] < a.window[1]
               for a in spec.tasks for b in spec.tasks)               # windows overlap
    assert len(spec.target_any_of) == 2 and spec.moving_obstacles and spec.input_bound
    margins = {m.name: m for m in design.certificate.margins}
    assert design.certificate.passed
    for task in spec.tasks:
        assert margins[task.name].passed and margins[task.name].margin > 0
    (cart,) = spec.moving_obstacles
    assert margins[f"avoids moving obstacle {cart.source}"].passed
    peak = design.to_json()["input_peak"]
    assert all(p < b for p, b in zip(peak["peak"], spec.input_bound))
    # the order is the design's: not the listed one
    assert design.task_plan.order != (0, 1, 2)


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("gcc") is None and shutil.which("clang") is None,
                    reason="no C compiler (install gcc or clang)")
def test_the_generated_c_meets_everything_and_verify_proves_it(design):
    result = stt.simulate(design, backend="c")
    assert result.satisfied and result.stayed_in_tube, result.to_json()
    assert all(task.met for task in result.tasks) and len(result.tasks) == 3
    assert result.min_obstacle_clearance > 0 and not result.collision
    assert all(u <= b for u, b in zip(result.max_abs_u, design.spec.input_bound))
    out = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "verify", str(SPEC),
                          "--all"], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout[-3000:]
    for name in ("tube.task_T1_reach", "tube.task_T2_reach", "tube.task_T3_stay",
                 "sampled.tube_kept", "sampled.input_bound"):
        assert f"PASS  {name}" in out.stdout, name


@pytest.mark.embedded
@pytest.mark.skipif(shutil.which("arm-none-eabi-gcc") is None
                    or shutil.which("qemu-system-arm") is None,
                    reason="needs the Debian packages gcc-arm-none-eabi, libnewlib-arm-none-eabi "
                           "and qemu-system-arm")
def test_the_composed_spec_on_the_cortex_m4f(design, tmp_path):
    """The single-precision C in the firmware's closed loop: every vector passes, every task
    is met and no obstacle (the cart included) is met on the target's own states, the
    tube is kept."""
    from stt_codegen.embedded.deploy import run_embedded
    report = run_embedded(design, tmp_path / "build")
    assert report["ok"] and report["vectors_failed"] == 0, report
    assert report["closed_loop_satisfied"] and not report["collision"]
    assert report["outside_tube_steps"] == 0 and report["min_clearance"] > 0
    assert [t["met"] for t in report["tasks"]] == [True, True, True]
    assert report["moving_clearance"] > 0
