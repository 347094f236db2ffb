"""A check's printed figures agree with its verdict.

On the U-maze of gymnasium-robotics' PointMaze (tests/specs/umaze-cascade.toml) verify
once printed ``FAIL adaptive.deployed[x1,L]: the deployed alpha stays in [0, 0.00578368]
... within the bound 0.00578368``: the enclosure's peak was 1.03e-10 relative above the
certified ``alpha_max`` (its brackets' rounding) and both printed the same.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import stt_codegen as stt
from stt_codegen.rounding import distinct
from stt_codegen.verification.command import _deployed_alpha_check as deployed_alpha_check

SPECS = Path(__file__).parent / "specs"


def test_distinct_prints_enough_digits_to_tell_two_numbers_apart():
    assert distinct(0.00578368332243275, 0.005783683321835951) == "0.0057836833224"
    assert distinct(0.25, 0.25) == "0.25"
    assert distinct(0.2501, 0.25) == "0.2501"
    assert distinct(1.23456, 2.0) == "1.23"
    assert float(distinct(0.1 + 0.2, 0.3)) == 0.1 + 0.2


def test_deployed_alpha_by_enclosure_or_by_induction():
    proved = deployed_alpha_check("x1,L", 0.5, 0.4, 0.0)
    assert proved.passed and proved.data["proved_by"] == "enclosure"
    hair_above = deployed_alpha_check("x1,L", 0.005783683321835951, 0.00578368332243275, 0.0)
    assert hair_above.passed and hair_above.data["proved_by"] == "induction"
    assert "1e-10 relative above" in hair_above.detail
    below_zero = deployed_alpha_check("x1,L", 0.5, 0.4, -1e-3)
    assert not below_zero.passed and "-0.001" in below_zero.detail


def test_umaze_adaptive_checks_pass_with_their_figures():
    """The U-maze's tube under a first-order plant (the cascade at 100 Hz is now refused by
    its own certificate; the tube and its alpha enclosure are the same, 1.03e-10 above
    ``alpha_max`` on x1,L)."""
    doc = tomllib.loads((SPECS / "umaze-cascade.toml").read_text())
    doc["plant"] = {"model": "single-integrator", "disturbance_amplitude": 0.1}
    del doc["state_space"]["velocity_bound"], doc["initial"]["velocity"], doc["assumptions"]
    report = stt.verify(stt.design_tube(stt.Spec.from_dict(doc)))
    deployed = [c for c in report.checks if c.name.startswith("adaptive.deployed")]
    assert len(deployed) == 4
    assert all(c.passed for c in deployed), [str(c) for c in deployed]
    assert deployed[0].data["proved_by"] == "induction"


def test_a_margin_failing_under_the_rounding_margin_says_why():
    """A certificate margin of 5e-10 passes nothing (it must exceed the enclosures'
    rounding, 1e-9) and printed alone it reads as positive: the text names the limit."""
    from stt_codegen.design.certificate.report import ROUNDING_MARGIN, _below_rounding
    assert ROUNDING_MARGIN == 1e-9
    assert "must exceed 1e-09" in _below_rounding(5e-10)
    assert _below_rounding(2e-9) == ""
