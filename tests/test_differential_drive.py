"""The differential-drive base as the look-ahead variant of law (13) (docs/differential-drive.md)."""

from __future__ import annotations

import ctypes
import math
import subprocess
import sys
import types
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.codegen.look_ahead_source import look_ahead_c_files, look_ahead_python_file
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.runtime.compiled import build_shared
from stt_codegen.runtime.differential_drive import base_rhs
from stt_codegen.tube import look_ahead_reference
from stt_codegen.tube.look_ahead import LookAhead, look_ahead_step
from stt_codegen.proofs import look_ahead as verify_look_ahead

SPEC = Path(__file__).parent / "specs" / "office-drive.toml"
DT = 1.0 / stt.load_spec(str(SPEC)).rate_hz     # the office's sampling period, s


def _doc(**plant) -> dict:
    """The office spec as a dict, with ``[plant]`` keys replaced."""
    import tomllib

    doc = tomllib.loads(SPEC.read_text())
    doc["plant"].update(plant)
    return doc


@pytest.fixture(scope="module")
def office():
    return stt.design_tube(stt.load_spec(str(SPEC)))


def test_the_spec_is_the_look_ahead_points_problem():
    spec = stt.load_spec(str(SPEC))
    assert spec.variant == "look-ahead" and spec.order == 1
    assert spec.input_names == ("v", "omega")
    # on MuJoCo too: [actuator] bounds (v, omega), not the wheels' actuators
    assert stt.load_spec(str(SPEC.with_name("office-drive-mujoco.toml"))).input_names == (
        "v", "omega")
    # the body's disc (radius 0.12 around the axle) lies within 0.12 + l of the point
    assert spec.robot.radius == pytest.approx(0.12 + 0.1)
    assert spec.state_space.lower == pytest.approx((0.22, 0.22))
    # the simulated base starts l behind its look-ahead point, facing initial.heading
    assert spec.drive.initial_axle(spec.initial_state) == pytest.approx((0.9, 1.0, 0.0))


@pytest.mark.parametrize("plant, field", [
    ({"axle_offset": None}, "plant.axle_offset"),
    ({"track_width": None}, "plant.track_width"),
    ({"disturbance_amplitude": 0.1}, "plant.disturbance_amplitude"),
    ({"wheel_radius_error": [1.5, 0.0]}, "plant.wheel_radius_error"),
    ({"slip": [0.1, -0.1, 0.0]}, "plant.slip"),
    ({"model": "single-integrator"}, "plant.axle_offset"),
])
def test_bad_drive_keys_are_refused_by_field(plant, field):
    doc = _doc(**{k: v for k, v in plant.items() if v is not None})
    for key, value in plant.items():
        if value is None:
            del doc["plant"][key]
    with pytest.raises(SpecError) as err:
        stt.Spec.from_dict(doc)
    assert err.value.field.startswith(field), err.value


def test_heading_only_for_a_differential_drive():
    doc = _doc(model="single-integrator")
    for key in ("axle_offset", "track_width", "wheel_radius_error", "slip"):
        del doc["plant"][key]
    with pytest.raises(SpecError, match="initial.heading"):
        stt.Spec.from_dict(doc)


def _point_g(theta: float, drive) -> np.ndarray:
    """``d p_dot / d u`` at a heading, numerically: law (13)'s ``u`` through the oracle's
    command and the base's kinematics (CasADi, evaluated), central differences."""
    state = np.array([0.3, -0.2, theta])
    rhs = base_rhs()

    def p_dot(u):
        cmd = look_ahead_reference.command(state[None], np.asarray(u)[None], drive.axle_offset)[0]
        sdot = np.array(rhs(state, cmd, drive.wheel_radius_error, drive.track_width,
                            [0, 0, 0])).ravel()
        h = np.array([math.cos(theta), math.sin(theta)])
        return sdot[:2] + drive.axle_offset * sdot[2] * np.array([-h[1], h[0]])

    eps = 1e-6
    return np.column_stack([(p_dot(e * eps) - p_dot(-e * eps)) / (2 * eps) for e in np.eye(2)])


@pytest.mark.parametrize("errors, offset, width", [((0.05, -0.05), 0.1, 0.16),
                                                    ((-0.08, 0.02), 0.2, 0.16),
                                                    ((0.03, 0.03), 0.05, 0.4)])
def test_the_derived_bounds_hold_the_sampled_g_and_are_attained(errors, offset, width):
    spec = stt.Spec.from_dict(_doc(wheel_radius_error=list(errors), axle_offset=offset,
                                   track_width=width))
    a = spec.assumptions
    eig, skew, coupling = [], [], []
    for theta in np.linspace(-math.pi, math.pi, 721):
        g = _point_g(theta, spec.drive)
        eig += list(np.linalg.eigvalsh((g + g.T) / 2))
        skew.append(abs((g[0, 1] - g[1, 0]) / 2))
        coupling.append(max(abs(g[0, 1]), abs(g[1, 0])))
    tol = 1e-7
    assert a.input_gain[0] - tol <= min(eig) and max(eig) <= a.input_gain[1] + tol
    assert max(skew) <= a.input_gain_skew + tol and max(coupling) <= a.input_gain_coupling + tol
    # tight: the sampled headings reach the bounds
    assert min(eig) == pytest.approx(a.input_gain[0], abs=1e-5)
    assert max(eig) == pytest.approx(a.input_gain[1], abs=1e-5)
    assert max(coupling) == pytest.approx(a.input_gain_coupling, abs=1e-5)
    # the slip's bound: forward, lateral and l times the turn rate, summed as documented
    s_v, s_lat, s_w = spec.drive.slip
    assert a.disturbance_bound == pytest.approx(math.hypot(s_v, s_lat + offset * s_w))


@pytest.mark.slow
def test_wheel_errors_that_lose_assumption_2_are_refused_before_designing():
    spec = stt.Spec.from_dict(_doc(wheel_radius_error=[0.2, -0.2], axle_offset=0.02,
                                   track_width=0.5))
    assert spec.assumptions.input_gain[0] < 0
    with pytest.raises(DesignError, match="plant.wheel_radius_error"):
        stt.design_tube(spec)
    check = verify_look_ahead.assumption2_differential_drive(spec)
    assert not check.passed and "Assumption 2 fails" in check.detail


@pytest.mark.slow
def test_the_deployed_command_inverts_the_kinematics_symbolically():
    assert verify_look_ahead.look_ahead_inverse().passed
    assert verify_look_ahead.assumption2_differential_drive(stt.load_spec(str(SPEC))).passed


def test_a_wrong_command_fails_the_symbolic_check(monkeypatch):
    """The check is on the deployed piece: a command with the turn rate's sign flipped (a
    plausible slip in a hand derivation) is caught."""
    heading, u_point, offset = ca.SX.sym("heading", 2), ca.SX.sym("u_point", 2), ca.SX.sym("l")
    c, s = heading[0], heading[1]
    wrong = ca.Function("base_command", [heading, u_point, offset],
                        [ca.vertcat(c * u_point[0] + s * u_point[1],
                                    (s * u_point[0] - c * u_point[1]) / offset)],
                        ["heading", "u_point", "axle_offset"], ["u"])
    monkeypatch.setattr(verify_look_ahead, "base_command", lambda: wrong)
    assert not verify_look_ahead.look_ahead_inverse().passed


def _points(count: int, seed: int) -> list:
    rng = np.random.default_rng(seed)
    return [(np.array([0.9 + 0.1 * rng.normal(), 1.0 + 0.1 * rng.normal(),
                       rng.uniform(-math.pi, math.pi)]), rng.uniform(0.0, 4.0),
             rng.uniform(0.0, 0.01, 4)) for _ in range(count)]


# (1.6, 16): the base's limits (office-base's); the points meet the clamp and points within it;
# with a reverse_speed of 0.2 m/s, v is clamped from below there
@pytest.mark.parametrize("bound, reverse", [(None, None), ((1.6, 16.0), None),
                                            ((1.6, 16.0), 0.2)])
def test_c_python_and_casadi_agree_bit_for_bit_and_with_the_oracle(office, bound, reverse):
    look_ahead = LookAhead(0.1, bound, reverse)
    function = look_ahead_step(office.tube, look_ahead)
    files = look_ahead_c_files(office.tube, look_ahead, "drive")
    lib = ctypes.CDLL(str(build_shared({k: v.encode() for k, v in files.items()}, "drive.c")))
    real_p = ctypes.POINTER(ctypes.c_double)
    step = lib.drive_step
    step.argtypes = [real_p, ctypes.c_double, ctypes.c_double, real_p, real_p, real_p]
    step.restype = ctypes.c_int
    module = types.ModuleType("drive")
    exec(look_ahead_python_file(office.tube, look_ahead, "drive")["drive.py"], module.__dict__)
    statuses, backing = set(), []
    for x, t, alpha in _points(200, seed=3):
        u, alpha_next = np.zeros(2), np.zeros(4)
        code = step(x.ctypes.data_as(real_p), t, DT, alpha.ctypes.data_as(real_p),
                    u.ctypes.data_as(real_p), alpha_next.ctypes.data_as(real_p))
        out = [np.array(v).ravel() for v in function(x, t, DT, alpha)]
        py_u, py_alpha, py_code = module.step(list(x), t, DT, list(alpha))
        assert np.array_equal(u, out[0]) and np.array_equal(alpha_next, out[1])
        assert np.array_equal(u, py_u) and np.array_equal(alpha_next, py_alpha)
        assert code == py_code
        ref_u, ref_alpha, ref_code = look_ahead_reference.look_ahead_status(
            office.tube, 0.1, bound, x[None], t, DT, alpha[None], reverse)
        np.testing.assert_allclose(u, ref_u[0], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(alpha_next, ref_alpha[0], rtol=1e-12, atol=1e-15)
        assert code == ref_code[0]
        statuses.add(code)
        backing.append(u[0])
    # the points reach inside and outside the tube, and the clamp where there is one
    assert {0, 1} <= statuses and ((3 in statuses) == (bound is not None))
    # v clamped from below at -reverse_speed (and backing up beyond it without one)
    assert min(backing) == -0.2 if reverse else min(backing) < -0.2


def test_a_command_at_the_wrong_axle_offset_differs_from_the_oracle(office):
    """The oracle is independent: the composition with another offset is told apart."""
    wrong = look_ahead_step(office.tube, LookAhead(0.12))
    (x, t, alpha), = _points(1, seed=5)
    ref_u = look_ahead_reference.look_ahead_status(office.tube, 0.1, None, x[None], t, DT,
                                                   alpha[None])[0][0]
    assert not np.allclose(np.array(wrong(x, t, DT, alpha)[0]).ravel(), ref_u, rtol=1e-6)


@pytest.mark.parametrize("errors", [(0.05, -0.05), (-0.05, 0.05), (0.05, 0.05),
                                    (-0.05, -0.05)])
def test_the_office_is_satisfied_at_the_corners_of_the_wheel_errors(errors):
    """With the slip at its amplitudes and the wheel errors at each corner of +-5 %."""
    design = stt.design_tube(stt.Spec.from_dict(_doc(wheel_radius_error=list(errors))))
    result = stt.simulate(design, backend="c", seed=7)
    assert result.satisfied and result.stayed_in_tube, result.summary()
    assert result.min_obstacle_clearance > 0 and result.max_abs_e < 1.0


@pytest.mark.slow
def test_verify_proves_the_sampled_loop_and_the_limits():
    spec = stt.Spec.from_dict({**_doc(), "actuator": {"input_bound": [1.6, 16.0]}})
    design = stt.design_tube(spec)
    assert design.tube.input_bound is None and design.look_ahead.input_bound == (1.6, 16.0)
    speed = math.hypot(*design.input_proof.peak[:1], 0.0)
    # omega from the heading the base can have: below the worst heading's |u| / l
    assert design.input_proof.peak[1] < 0.9 * speed / 0.1
    report = stt.verify(design)
    names = {c.name: c for c in report.checks}
    assert report.passed, [c for c in report.checks if not c.passed]
    for name in ("look_ahead.inverse", "assumption2.differential_drive", "sampled.tube_kept",
                 "sampled.input_bound"):
        assert names[name].passed, name
    run = stt.simulate(design, backend="c")
    assert run.satisfied and all(u <= b for u, b in zip(run.max_abs_u, (1.6, 16.0)))
    assert all(u <= p for u, p in zip(run.max_abs_u, design.input_proof.peak))


@pytest.mark.slow
def test_a_bound_too_tight_names_the_prescribed_time_that_works():
    """0.8 m/s is below the best design's proved 1.10 at 200 Hz (the via tube with cruise
    segments): refused, naming the prescribed_time that works."""
    spec = stt.Spec.from_dict({**_doc(), "actuator": {"input_bound": [0.8, 16.0]}})
    with pytest.raises(DesignError, match=r"base's command \(v, omega\).*prescribed_time = "):
        stt.design_tube(spec)


@pytest.mark.slow          # about 9 s; test_verify_proves_the_sampled_loop_and_the_limits stays fast
def test_a_gain_far_above_the_derived_one_fails_the_sampled_check(office):
    bad = replace(office, tube=replace(office.tube, gain=20 * office.tube.gain))
    names = {c.name: c for c in stt.verify(bad).checks}
    assert not names["sampled.tube_kept"].passed


def test_generation_is_deterministic_and_names_its_source(office, tmp_path):
    first = stt.generate(office, tmp_path / "a")
    second = stt.generate(office, tmp_path / "b")
    assert [p.name for p in first] == [p.name for p in second]
    for a, b in zip(first, second):
        assert a.read_bytes() == b.read_bytes()
    source = (tmp_path / "a" / "office_drive.c").read_text()
    assert "GENERATED FILE" in source and "look_ahead_source" in source
    assert str(tmp_path) not in source and "/work" not in source


@pytest.mark.parametrize("reverse", [None, 0.2])
def test_the_single_precision_c_compiles_strictly(office, reverse):
    files = look_ahead_c_files(office.tube, LookAhead(0.1, (1.6, 16.0), reverse), "drive",
                               "single")
    assert ("REVERSE_SPEED" in files["drive.h"]) == (reverse is not None)
    build_shared({k: v.encode() for k, v in files.items()}, "drive.c")


def test_law_13s_firmware_loop_refuses_the_variant_by_name(office):
    from stt_codegen.embedded.deploy import run_embedded

    with pytest.raises(SpecError, match="look-ahead variant"):
        run_embedded(office)


@pytest.mark.embedded
def test_the_office_on_the_cortex_m4f_is_satisfied_like_the_host(office):
    from stt_codegen.embedded.look_ahead_loop import run_look_ahead_embedded

    report = run_look_ahead_embedded(office)
    assert report["satisfied"] and report["outside_position"] == report["invalid"] == 0
    assert all(500 < c < 5000 for c in report["instructions_per_step"])
    host = stt.simulate(office, backend="c")        # double controller, same base and slip
    assert abs(report["reach_time"] - host.reach_time) <= 0.02
    assert abs(report["min_clearance"] - host.min_obstacle_clearance) <= 2e-3
    final_point = look_ahead_reference.point(np.array([report["final_state"]]), 0.1)[0]
    np.testing.assert_allclose(final_point, host.trajectory.x[-1], atol=2e-3)


def test_the_command_line_refuses_a_missing_key_with_exit_2(tmp_path):
    text = SPEC.read_text().replace("axle_offset = 0.1\n", "")
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    run = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "design", str(bad)],
                         capture_output=True, text=True)
    assert run.returncode == 2 and "plant.axle_offset" in run.stderr
    assert "Traceback" not in run.stderr


MUJOCO_SPEC = SPEC.with_name("office-drive-mujoco.toml")


def test_the_office_on_mujoco_is_satisfied_without_contact():
    """The project's MuJoCo base (tests/specs/office-drive.xml: wheels on the floor, a
    caster, the obstacles at their real size) driven by the generated C."""
    design = stt.design_tube(stt.load_spec(str(MUJOCO_SPEC)))
    result = stt.simulate(design, backend="c")
    assert result.satisfied and result.stayed_in_tube and result.contacts == 0
    assert result.min_obstacle_clearance > 0


def test_the_mujoco_base_turns_commands_into_wheel_speeds():
    """Driven open loop at v = 0.5 m/s for 2 s, then turning at omega = 1 rad/s, the base
    moves as the kinematics say (the wheels grip: within 3 % of 1 m and of 1 rad)."""
    from stt_codegen.runtime.plants import spec_plant

    spec = stt.load_spec(str(MUJOCO_SPEC))
    plant = spec_plant(spec)
    start = plant.reset([1.0, 1.0, 0.0])
    for k in range(100):
        states, _ = plant.advance(0.02 * k, [0.5, 0.0], 0.02)
    assert states[-1][0] - start[0] == pytest.approx(1.0, rel=0.03)
    assert abs(states[-1][1] - start[1]) < 0.01
    heading = states[-1][2]
    for k in range(50):
        states, _ = plant.advance(2.0 + 0.02 * k, [0.0, 1.0], 0.02)
    assert states[-1][2] - heading == pytest.approx(1.0, rel=0.03)


def test_a_mujoco_base_needs_its_wheel_radius():
    import tomllib

    doc = tomllib.loads(MUJOCO_SPEC.read_text())
    del doc["plant"]["wheel_radius"]
    with pytest.raises(SpecError, match="plant.wheel_radius"):
        stt.Spec.from_dict(doc)


def test_a_tube_through_the_desks_is_rejected_by_the_certificate(office):
    """The tube designed for the empty room, checked against the office: it crosses the
    desks (inflated by the body's radius plus the axle offset), and the check says which."""
    from stt_codegen.design.search import check_tube

    doc = _doc()
    doc["obstacles"] = []
    straight = stt.design_tube(stt.Spec.from_dict(doc)).tube
    check = check_tube(straight, office.spec)
    assert not check.passed and "obstacle" in check.reason
    assert check_tube(office.tube, office.spec).passed
