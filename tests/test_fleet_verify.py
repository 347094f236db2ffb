"""``verify`` of a fleet (stt_codegen/verification/fleet.py, docs/fleets.md): every robot's
checks and every pair certified again from the recomputed certificates."""

from __future__ import annotations

import json

import pytest

import stt_codegen as stt
from stt_codegen.cli import main
from stt_codegen.design.fleet import FleetDesign


@pytest.mark.slow
def test_the_bundled_pair_passes_with_the_designs_margins():
    designed = stt.design_fleet("swap-fleet")
    report = stt.verify_fleet(designed)
    assert report.passed and sorted(report.robots) == ["east", "west"]
    assert all(r.passed and len(r.checks) > 10 for r in report.robots.values())
    # the pairs certified again from the certificates verify recomputes: the design's
    assert [(p.pair, p.margin, p.t_start) for p in report.pairs] == \
        [(p.pair, p.margin, p.t_start) for p in designed.pairs]
    assert "every check passed" in report.summary()


@pytest.mark.slow
def test_robots_designed_apart_fail_on_their_pair_only():
    # each robot certified alone, but their tubes cross: every robot's report passes and
    # the pair fails, naming both robots and the interval
    fleet = stt.load_fleet("swap-fleet")
    alone = {r.name: stt.design_tube(r.spec) for r in fleet.robots}
    report = stt.verify_fleet(FleetDesign(fleet, alone, tuple(alone), ()))
    assert all(r.passed for r in report.robots.values())
    (pair,) = report.pairs
    assert not pair.passed and not report.passed and pair.t_end > pair.t_start
    assert (f"FAIL: east and west: their tubes, grown by both radii, may meet on "
            f"[{pair.t_start:.4f}, {pair.t_end:.4f}]") in " ".join(report.summary().split())
    assert report.to_json()["pairs"][0]["passed"] is False


@pytest.mark.slow
def test_the_command_verifies_a_fleet_and_prints_json(capsys):
    assert main(["verify", "swap-fleet", "--quiet", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["passed"] and sorted(out["robots"]) == ["east", "west"]
    assert all(c["passed"] for checks in out["robots"].values() for c in checks)
    assert [p["pair"] for p in out["pairs"]] == [["east", "west"]]


def test_a_plant_for_a_fleet_exits_2_naming_the_flag(capsys):
    assert main(["verify", "swap-fleet", "--plant", "single-integrator"]) == 2
    err = capsys.readouterr().err
    assert "--plant" in err and "each robot of a fleet has its own" in err
    assert "Traceback" not in err
