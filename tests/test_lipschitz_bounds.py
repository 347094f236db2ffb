"""``[assumptions] input_gain_lipschitz`` and ``drift_lipschitz``: what each plant model
derives, the rules for declared values (one ``SpecError`` naming the field per rule), and
that the derived constants hold for the model's own ``g`` and ``f``."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_assumptions import BASE as PLANE  # a 4 x 4 m single-integrator arena

from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import load_spec, parse_spec

CASES = Path(__file__).resolve().parents[1] / "stt_codegen" / "cases"
ROBOT = (CASES / "omnirobot-s1.toml").read_text()


def robot_with(assumptions: str):
    return parse_spec(ROBOT + "\n[assumptions]\n" + assumptions + "\n")


def rotation(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_the_robot_derives_its_own_bounds_and_they_hold():
    a = load_spec(CASES / "omnirobot-s1.toml").assumptions
    assert a.input_gain_lipschitz == (0.0, 0.0, 1.0)
    assert a.drift_lipschitz == (0.0, 0.0, 0.0)
    assert "input_gain_lipschitz" not in a.declared
    # g = R(x3): |g(x) - g(y)|_2 <= L . |x - y| on random pairs, and L3 = 1 is not loose
    rng = np.random.default_rng(3)
    ratios = []
    for _ in range(2000):
        x, y = rng.uniform(-1.2, 1.2, 2)
        change = np.linalg.norm(rotation(x) - rotation(y), 2)
        assert change <= a.input_gain_lipschitz[2] * abs(x - y) + 1e-12
        ratios.append(change / abs(x - y))
    assert max(ratios) > 0.99


def test_the_linear_model_derives_the_columns_of_a():
    spec = parse_spec(PLANE + '[plant]\nmodel = "linear"\na = [[0, 3], [-4, 0.5]]\n'
                      'g = [[2, 0.5], [0, 1]]\n')
    a = spec.assumptions
    assert a.input_gain_lipschitz == (0.0, 0.0)
    assert a.drift_lipschitz[0] == pytest.approx(4.0) and a.drift_lipschitz[0] >= 4.0
    assert a.drift_lipschitz[1] == pytest.approx(math.hypot(3.0, 0.5))
    # |a (x - y)| <= sum_j L_j |x_j - y_j| on random pairs
    matrix = np.array([[0, 3], [-4, 0.5]])
    rng = np.random.default_rng(5)
    for _ in range(500):
        d = rng.normal(size=2)
        assert np.linalg.norm(matrix @ d) <= np.dot(a.drift_lipschitz, np.abs(d)) + 1e-12
    single = parse_spec(PLANE).assumptions
    assert single.input_gain_lipschitz == (0.0, 0.0) and single.drift_lipschitz == (0.0, 0.0)


def test_declared_bounds_are_used_and_noted():
    a = robot_with("input_gain_lipschitz = [0, 0, 1.5]").assumptions
    assert a.input_gain_lipschitz == (0.0, 0.0, 1.5) and "input_gain_lipschitz" in a.declared
    assert any("input_gain_lipschitz" in note for note in a.notes)


def test_a_declared_bound_on_g_drops_the_models_lipschitz_unless_declared_too():
    wide = "input_gain = [0.362, 1]\ninput_gain_skew = 0.933\ninput_gain_coupling = 0.933"
    assert robot_with(wide).assumptions.input_gain_lipschitz is None
    assert robot_with(wide + "\ninput_gain_lipschitz = [0, 0, 1]"
                      ).assumptions.input_gain_lipschitz == (0.0, 0.0, 1.0)
    drift = robot_with("drift_bound = 0.5").assumptions
    assert drift.drift_lipschitz is None and drift.input_gain_lipschitz == (0.0, 0.0, 1.0)


@pytest.mark.parametrize("text, field, words", [
    ("input_gain_lipschitz = [0, 0, 0.5]", "assumptions.input_gain_lipschitz[2]", "below 1"),
    ("input_gain_lipschitz = [0, 1]", "assumptions.input_gain_lipschitz", "one per state (3)"),
    ("drift_lipschitz = [0, 0, 0, 0]", "assumptions.drift_lipschitz", "one per state (3)"),
    ("drift_lipschitz = [0, -1, 0]", "assumptions.drift_lipschitz", ""),
    ("input_gain_lipschitz = 1.0", "assumptions.input_gain_lipschitz", ""),
])
def test_bad_declarations_name_the_field(text, field, words):
    with pytest.raises(SpecError) as info:
        robot_with(text)
    assert info.value.field.startswith(field) and words in info.value.reason


def test_a_model_without_equations_takes_the_declared_bounds_as_they_are(tmp_path):
    path = CASES / "pointmaze-umaze.toml"
    assert load_spec(path).assumptions.input_gain_lipschitz is None
    text = path.read_text()
    declared = text.replace("drift_bound = 0.1", "drift_bound = 0.1\n"
                            "input_gain_lipschitz = [0.05, 0.05]")
    assert declared != text
    (tmp_path / "pointmaze-umaze.xml").write_bytes((CASES / "pointmaze-umaze.xml").read_bytes())
    (tmp_path / "declared.toml").write_text(declared)
    assert load_spec(tmp_path / "declared.toml").assumptions.input_gain_lipschitz == (0.05, 0.05)


def test_second_order_models_refuse_the_keys():
    text = (CASES / "second-order-s1.toml").read_text()
    with pytest.raises(SpecError) as info:
        parse_spec(text.replace("drift_bound = 0.0", "drift_bound = 0.0\n"
                                "drift_lipschitz = [0, 0]"))
    assert info.value.field == "assumptions.drift_lipschitz"


def test_a_bad_declaration_on_the_command_line_is_exit_2(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(ROBOT + "\n[assumptions]\ninput_gain_lipschitz = [0, 0, 0.5]\n")
    out = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "verify", str(path)],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 2 and "input_gain_lipschitz" in out.stderr
    assert "Traceback" not in out.stderr


@pytest.mark.slow
def test_verify_says_not_the_checks_caution_only_about_a_member_of_the_declared_class():
    """The robot's geometry with a wall, its true bounds for the heading range declared
    (``g = R(x3)``): without its Lipschitz bound the class has a jumping member that leaves
    the tube, and ``verify`` says so; with ``input_gain_lipschitz = [0, 0, 1]`` the same
    verdict, but no member of that class is found, so the caution is not ruled out. Both
    times ``verify`` adds that the model's own ``g``, evaluated on the tube, passes."""
    from stt_codegen.verification.command import verify_spec
    wall = (Path(__file__).parent / "specs" / "wall-gap-s1.toml").read_text()
    declared = ("\n[assumptions]\ninput_gain = [0.362, 1]\ninput_gain_skew = 0.933\n"
                "input_gain_coupling = 0.933\n")
    kept = {}
    for label, extra in (("jumping", ""), ("lipschitz", "input_gain_lipschitz = [0, 0, 1]\n")):
        checks = {c.name: c for c in verify_spec(parse_spec(wall + declared + extra))}
        kept[label] = checks["sampled.tube_kept"]
    assert not kept["jumping"].passed and not kept["lipschitz"].passed
    member = kept["jumping"].data["class_counterexample"]
    assert member is not None and "g Lipschitz" not in member["strategy"]
    assert "not the check's caution" in kept["jumping"].detail
    assert "g on each interval an extreme member" in kept["jumping"].detail
    assert kept["lipschitz"].data["class_counterexample"] is None
    assert "not the check's caution" not in kept["lipschitz"].detail
    assert "does not use input_gain_lipschitz" in kept["lipschitz"].detail
    assert "does not use input_gain_lipschitz" not in kept["jumping"].detail
    # the model's own g, evaluated on the tube, passes: verify says so, both times
    for check in kept.values():
        assert ("omnidirectional model's own g, its bounds evaluated on the tube per "
                "sampling interval, passes at 1000 Hz" in check.detail)
        assert "drop the declared input_gain, input_gain_skew, input_gain_coupling" in \
            check.detail


def test_held_members_contract_where_alternating_them_grows():
    """Why a check valid for plants whose ``g`` jumps cannot pass the wall's declared class
    (docs/sampled-data.md, "Lipschitz bounds and the check"): at ``t = 0`` two members of
    the class, ``g13 = -g31 = -+0.933``, each make the linearized sampled step of law (13)
    contract, and alternating them every sample makes it grow; a Lipschitz bound of 1 in
    ``x3`` forbids the alternation (it moves ``g`` by 1.87 per sample)."""
    from stt_codegen import design_tube
    from stt_codegen.design.samples import sample_tube
    from stt_codegen.verification.class_search import within_class
    wall = (Path(__file__).parent / "specs" / "wall-gap-s1.toml").read_text()
    declared = ("\n[assumptions]\ninput_gain = [0.362, 1]\ninput_gain_skew = 0.933\n"
                "input_gain_coupling = 0.933\n")
    spec = parse_spec(wall + declared)
    tube = design_tube(spec).tube
    samples = sample_tube(tube)
    half = (samples.gamma_upper[0] - samples.gamma_lower[0]) / 2
    dt = 1.0 / tube.rate_hz
    steps = []
    for sign in (1.0, -1.0):
        g = np.diag([0.362, 1.0, 0.362])
        g[0, 2], g[2, 0] = -sign * 0.933, sign * 0.933
        assert within_class(g, spec.assumptions)
        # e+ = e - 2 k dt H^-1 g H^-1 phi(e), phi(e) = 2 e + O(e^3)
        steps.append(np.eye(3) - 4.0 * tube.gain * dt * (g / half[:, None]) / half[None, :])
    held = [max(abs(np.linalg.eigvals(a))) for a in steps]
    alternating = max(abs(np.linalg.eigvals(steps[0] @ steps[1]))) ** 0.5
    # x2 alone contracts by 0.91 per sample, the (x1, x3) block by 0.76
    assert max(held) < 0.92 and alternating > 1.03
