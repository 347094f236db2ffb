"""``auto`` prefers via points when the paper's tube asks for more gain than it has (issue 20).

Law (13) has one gain, bounded by the sampled loop at the tube's narrowest point
(docs/decisions.md, decision 15). A tube that squeezes one dimension to millimetres while
another moves fast, or lets a circumvent go faster than the gain follows, leaves the state
near its wall in closed loop however tight the width bound: ``tracking_demand`` estimates
that, and ``auto`` then takes via points if they ask for less.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from stt_codegen.bench.arenas import generate_arena
from stt_codegen.design.search import design_tube
from stt_codegen.design.tracking import TRACKING_ERROR, tracking_demand
from stt_codegen.runtime.simulate import run_closed_loop
from stt_codegen.spec.loader import load_spec

SPECS = Path(__file__).parent / "specs"


def _method(spec, method):
    return dataclasses.replace(spec, tube=dataclasses.replace(spec.tube, method=method))


def test_bundled_cases_keep_the_papers_tube(case):
    spec = load_spec(case)
    found = design_tube(spec)
    assert found.method == "paper"
    assert tracking_demand(found.tube, found.certificate, spec).ratio < 1.0


@pytest.mark.parametrize("spec", [generate_arena(0, 7).to_spec(),
                                  load_spec(SPECS / "shifted-arena-1e6.toml")],
                         ids=["arena-0-7", "shifted-arena-1e6"])
def test_a_tube_the_gain_cannot_follow_gives_way_to_via_points(spec):
    """Arena 7 of seed 0: the paper's tube squeezes x2 to 6.7 mm against the wall while x1
    moves at 0.5 m/s; its state rode at |e| = 0.93. The demand says so, and auto takes the
    via tube, whose state stays near the middle."""
    paper = design_tube(_method(spec, "paper"))
    demand = tracking_demand(paper.tube, paper.certificate, spec)
    assert demand.ratio > 1.0
    assert run_closed_loop(spec, paper.tube, backend="reference").max_abs_e > TRACKING_ERROR
    chosen = design_tube(spec)
    assert chosen.method == "via"
    assert tracking_demand(chosen.tube, chosen.certificate, spec).ratio < 1.0
    result = run_closed_loop(spec, chosen.tube, backend="reference")
    assert result.satisfied and result.max_abs_e < 0.1


def test_the_demand_does_not_depend_on_the_declared_gain_range():
    """k lambda* is the same for every [g_min, g_max] (k = w^2 / (8 dt (g_min + g_max)),
    lambda* their middle): the demand measures the tube, not the plant's uncertainty."""
    robot = load_spec("omnirobot-s2")
    spec, wide = (dataclasses.replace(robot, assumptions=dataclasses.replace(
        robot.assumptions, input_gain=gains)) for gains in ((1.0, 1.0), (0.36, 1.0)))
    a, b = design_tube(spec), design_tube(wide)
    assert b.gain == pytest.approx(a.gain * 2.0 / 1.36)
    assert (tracking_demand(b.tube, b.certificate, wide).ratio
            == pytest.approx(tracking_demand(a.tube, a.certificate, spec).ratio))
