"""``stt-codegen verify`` on the paper's cases, and on specs built to break each check."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys

import pytest
from conftest import designed

from stt_codegen.design.failures import FailureKind
from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError, SpecError
from stt_codegen.spec.loader import parse_spec
from stt_codegen.tube.parameters import Circumvent
from stt_codegen.verification.command import verify_design, verify_spec


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args], capture_output=True,
                          text=True, timeout=600)


def failed(checks) -> dict[str, str]:
    return {c.name: c.detail for c in checks if not c.passed}


# about 8 s a case: the slow tier (the fast one keeps the tests of each check, tests/test_verify_*.py)
@pytest.mark.slow
def test_all_checks_pass_on_the_paper_cases(case):
    spec, design, _ = designed(case)
    checks = verify_design(spec, design)
    assert failed(checks) == {}
    names = {c.name for c in checks}
    for expected in ("lemma3.3.reach.continuity", "lemma3.3.bump.rate_bound",
                     "theorem4.1.epsilon_jacobian.n3", "theorem4.1.outer_product_reading.n2",
                     "assumption2.omnidirectional", "adaptive.upper_bound[x2,L]",
                     "tube.non-empty", "tube.avoids_obstacle_3",
                     "tube.inside_target_after_t_c"):
        assert expected in names, expected


@pytest.mark.slow
def test_cli_json_and_exit_code():
    out = run("verify", "omnirobot-s2", "--json")
    assert out.returncode == 0, out.stderr
    assert out.stderr == ""                        # no progress, no warning: JSON only
    data = json.loads(out.stdout)
    assert data[0]["name"] == "lemma3.3.reach.continuity"
    assert all(set(d) == {"name", "passed", "detail"} and d["passed"] for d in data)
    assert len(data) > 30


SPEC = """
name = "breaker"
prescribed_time = 9.0
[state_space]
lower = [0.0, 0.0, -1.2]
upper = [5.0, 5.0, 1.2]
[initial]
lower = [0.0, 0.0, -0.1]
upper = [0.5, 0.5, 0.1]
half_width = [0.2, 0.2, 0.05]
[target]
lower = [4.5, 4.5, -1.2]
upper = [5.0, 5.0, 1.2]
half_width = [0.2, 0.2, 0.5]
[tube]
circumvent_sharpness = 0.1
[plant]
model = "omnidirectional"
"""


def test_tiny_nu_empties_the_tube_near_the_target():
    spec = parse_spec(SPEC.replace("circumvent_sharpness = 0.1",
                                   "circumvent_sharpness = 0.1\nsmoothness = 1.0"))
    bad = failed(verify_spec(spec))
    assert list(bad) == ["tube.design"]
    assert "non-empty fails" in bad["tube.design"] or "target" in bad["tube.design"]


def test_an_obstacle_the_tube_cannot_get_around():
    wall = SPEC + "[[obstacles]]\nlower = [2.0, 0.0]\nupper = [2.5, 5.0]\n"
    bad = failed(verify_spec(parse_spec(wall)))
    assert list(bad) == ["tube.design"]
    assert "no choice of circumvent dimension and side passes" in bad["tube.design"]
    assert "obstacle 0" in bad["tube.design"]


@pytest.mark.slow
def test_heading_range_reaching_pi_over_2_fails_assumption_2(tmp_path):
    wide = SPEC.replace("lower = [0.0, 0.0, -1.2]\nupper = [5.0, 5.0, 1.2]",
                        "lower = [0.0, 0.0, -1.6]\nupper = [5.0, 5.0, 1.6]")
    path = tmp_path / "wide.toml"
    path.write_text(wide)
    # the plant is known (eq. (14)): design refuses it, and verify reports why
    with pytest.raises(DesignError, match="pi/2") as refused:
        design_tube(parse_spec(wide))
    assert refused.value.kind is FailureKind.PLANT
    bad = failed(verify_spec(parse_spec(wide)))
    assert list(bad) == ["tube.design"] and "Assumption 2" in bad["tube.design"]
    out = run("verify", str(path))     # no design: the reason, as every command gives it
    assert out.returncode == 1 and out.stdout == ""
    assert out.stderr.startswith("error: ") and "pi/2" in out.stderr
    assert "Traceback" not in out.stderr
    # the symbolic check names the point where positivity is lost, for the tube designed
    # as if for another plant
    spec = parse_spec(wide)
    tube = design_tube(dataclasses.replace(spec, plant_model="single-integrator")).tube
    bad = failed(verify_design(spec, tube))
    assert "assumption2.omnidirectional" in bad
    assert "1.5707963" in bad["assumption2.omnidirectional"] or "pi/2" in \
        bad["assumption2.omnidirectional"]
    ok = run("verify", str(path), "--plant", "single-integrator")
    assert ok.returncode == 0, ok.stdout[-2000:]


def test_parameters_that_make_alpha_unbounded_are_rejected_or_fail():
    """kappa = 0 (alpha grows like t^(1/3)) is refused at validation; a circumvent active
    at t = 0 below the start puts psi(0) <= 0: alpha_dot is infinite, Lemma 3.3 fails."""
    with pytest.raises(SpecError, match="kappa: must be positive"):
        parse_spec(SPEC.replace("[tube]", "[tube]\nkappa = 0.0"))
    spec, design, _ = designed("omnirobot-s1")
    early = Circumvent(obstacle=0, dimension=1, side="upper", start=-1.0, end=2.0,
                       height=1.2, base=5.0, sharpness=0.1)          # beta_U(0) < rho_L(0): a conflict at t=0
    broken = dataclasses.replace(design, circumvents=(early,))
    bad = failed(verify_design(spec, broken))
    assert "adaptive.singularity[x2,L]" in bad
    assert "psi(0) = " in bad["adaptive.singularity[x2,L]"]


def test_bad_plant_option_is_exit_2():
    out = run("verify", "omnirobot-s1", "--plant", "bicycle")
    assert out.returncode == 2 and "--plant" in out.stderr and "Traceback" not in out.stderr
