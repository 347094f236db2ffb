"""``[actuator] reverse_speed``: a differential-drive base asked to back up no faster than
it may (docs/differential-drive.md, "Backing up").

The spec refuses the key where it means nothing or contradicts ``v_max``; the design proves
the backing up from the heading the base can have, refuses a spec whose every tube backs up
faster (naming the ``reverse_speed`` that is then certified), and refuses 0, which no tube
meets; the generated controller clamps ``v`` from below there, and the closed loop never
reaches the clamp.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.design.look_ahead import NEVER_BACKS_UP
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.spec.loader import parse_spec

SPECS = Path(__file__).parent / "specs"
BOUND = "input_bound = [1.2, 1.5]\n"


def _agv(reverse: str) -> stt.Spec:
    """The warehouse AGV (``tests/specs/agv-warehouse.toml``) with ``reverse_speed``."""
    text = (SPECS / "agv-warehouse.toml").read_text()
    assert BOUND in text
    return parse_spec(text.replace(BOUND, BOUND + f"reverse_speed = {reverse}\n"))


def test_the_key_is_a_bases_and_within_v_max():
    with pytest.raises(SpecError, match=r"actuator.reverse_speed.*exceeds input_bound's v_max"):
        _agv("1.5")
    with pytest.raises(SpecError, match=r"actuator.reverse_speed.*non-negative"):
        _agv("-0.1")
    text = (SPECS / "nonlinear-reach-avoid-drive.toml").read_text()
    omni = text.replace('model = "differential-drive"\naxle_offset = 0.3\ntrack_width = 0.3',
                        'model = "single-integrator"').replace(
        "input_bound = [10.0, 5.0]", "input_bound = [10.0, 5.0]\nreverse_speed = 1.0").replace(
        "heading = 0.0\n", "")
    assert omni != text
    with pytest.raises(SpecError, match=r"actuator.reverse_speed.*differential-drive base"):
        parse_spec(omni)
    sensed = (SPECS / "hall-crossing-drive.toml").read_text()
    with pytest.raises(SpecError, match=r"actuator.reverse_speed.*not available with \[sensing\]"):
        parse_spec(sensed.replace("input_bound = [1.0, 5.0]",
                                  "reverse_speed = 0.5\ninput_bound = [1.0, 5.0]"))
    assert _agv("0.2").reverse_speed == 0.2


def test_zero_is_refused_naming_the_reverse_speed_that_is_certified():
    """No tube meets ``v >= 0`` (the command's box at a stop holds backward commands): the
    refusal says so and names the ``reverse_speed`` the design allowed to back up needs,
    which is then certified, and its proof backs up no faster."""
    with pytest.raises(DesignError) as refused:
        stt.design_tube(_agv("0"))
    assert NEVER_BACKS_UP in str(refused.value)
    named = refused.value.advice["actuator.reverse_speed"]
    assert 0.0 < named < 1.2 and f"actuator.reverse_speed = {named:g} m/s" in str(refused.value)
    design = stt.design_tube(_agv(named))
    assert 0.0 < design.input_proof.backward <= named
    assert design.input_proof.reverse_limit == named


def test_a_reverse_speed_below_every_tube_is_refused_and_the_named_one_holds():
    """0.05 m/s is below what every candidate within ``input_bound`` backs up at: refused
    naming the lowest candidate's, which is then certified."""
    with pytest.raises(DesignError, match=r"within actuator.reverse_speed = 0.05 m/s.*backs "
                                          r"the base up at") as refused:
        stt.design_tube(_agv("0.05"))
    named = refused.value.advice["actuator.reverse_speed"]
    assert named > 0.05
    design = stt.design_tube(_agv(named))
    assert design.input_proof.backward <= named
    # within the bound: a reverse_speed just under the proof's is refused
    with pytest.raises(DesignError):
        stt.design_tube(_agv(design.input_proof.backward * 0.999))


def test_the_closed_loop_backs_up_no_faster_than_proved_and_is_never_clamped():
    """The generated C on the host, three seeds of slip: ``v`` never below the proof's
    ``-backward``, no step clamped, satisfied; the controller carries the lower end."""
    design = stt.design_tube(_agv("0.2"))
    assert design.look_ahead.reverse_speed == 0.2
    assert design.look_ahead.input_lower == (-0.2, -1.5)
    for seed in range(3):
        run = stt.simulate(design, backend="c", seed=seed)
        v = np.asarray(run.trajectory.u)[:, 0]
        assert run.satisfied and run.clamped_steps == 0, run.summary()
        assert v.min() >= -design.input_proof.backward


@pytest.mark.slow
def test_verify_reports_the_backing_up():
    design = stt.design_tube(_agv("0.2"))
    checks = {c.name: c for c in stt.verify(design).checks}
    bound = checks["sampled.input_bound"]
    assert bound.passed and "backing up at most" in bound.detail
    assert bound.data["reverse_speed"] == 0.2
    assert 0.0 < bound.data["backward"] <= 0.2


def test_stlpys_unicycle_with_v_at_least_zero_is_refused_with_the_reason():
    """stlpy's NonlinearReachAvoid as a base with the unicycle's own bounds, ``v`` in ``[0,
    10]``: refused, saying why ``v >= 0`` is not certified and what the base allowed to
    back up gives (its own refusal: no circumvent fits and the via tube is too fast for
    100 Hz)."""
    text = (SPECS / "nonlinear-reach-avoid-drive.toml").read_text()
    spec = parse_spec(text.replace("input_bound = [10.0, 5.0]",
                                   "input_bound = [10.0, 5.0]\nreverse_speed = 0.0"))
    with pytest.raises(DesignError) as refused:
        stt.design_tube(spec)
    message = str(refused.value)
    assert message.startswith("actuator.reverse_speed = 0 is not certified: " + NEVER_BACKS_UP)
    assert ("allowed to back up (reverse_speed omitted), obstacle 0 cannot be circumvented"
            in message)



@pytest.mark.embedded
def test_the_agv_backing_up_on_the_cortex_m4f_is_satisfied_like_the_host():
    """The single-precision C with the clamp's lower end on the emulated Cortex-M4F: no
    step clamped, the reach time the host's to a sample."""
    from stt_codegen.embedded.look_ahead_loop import run_look_ahead_embedded

    design = stt.design_tube(_agv("0.2"))
    report = run_look_ahead_embedded(design)
    assert report["satisfied"] and report["input_clamped"] == report["invalid"] == 0
    host = stt.simulate(design, backend="c")
    assert abs(report["reach_time"] - host.reach_time) <= 1.0 / design.tube.rate_hz


@pytest.mark.slow
def test_a_fleets_bases_keep_their_reverse_speed():
    """``warehouse-fleet`` with its three bases given ``reverse_speed = 0.4``: the fleet
    design plans each way without ``[actuator]`` (``Spec.without_actuator`` drops the key
    with ``input_bound``), then proves each base's backing up within it; certified, each
    base's controller clamping there."""
    import tomllib

    from stt_codegen.spec.fleet import FleetSpec

    path = Path(stt.__file__).parent / "cases" / "fleets" / "warehouse-fleet.toml"
    doc = tomllib.loads(path.read_text())
    for robot in doc["robots"]:
        if "actuator" in robot:
            robot["actuator"] = dict(robot["actuator"], reverse_speed=0.4)
    design = stt.design_fleet(FleetSpec.from_dict(doc))
    assert design.certified
    bases = [d for d in design.designs.values() if d.spec.reverse_speed is not None]
    assert len(bases) == 3
    for base in bases:
        assert base.look_ahead.reverse_speed == 0.4
        assert base.input_proof.reverse_limit == 0.4
        assert 0.0 < base.input_proof.backward <= 0.4
