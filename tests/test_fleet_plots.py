"""The fleet in time slices (stt_codegen/runtime/fleet_plots.py, docs/fleets.md)."""

from __future__ import annotations

import pytest

import stt_codegen as stt
from stt_codegen.errors import SpecError
from stt_codegen.runtime.fleet_plots import MAX_SLICES, fleet_figure


def test_a_fleet_spec_is_not_a_design():
    with pytest.raises(TypeError, match="call stt_codegen.design_fleet first"):
        stt.plot_fleet(stt.load_fleet("swap-fleet"), "x.png")


@pytest.mark.slow
def test_every_slice_draws_each_robot_its_tube_and_its_body(tmp_path):
    designed = stt.design_fleet("swap-fleet")
    run = stt.simulate_fleet(designed, backend="reference")
    fig = fleet_figure(designed, run, slices=4)
    assert [ax.get_title() for ax in fig.axes] == [
        f"t = {t:.2f} s" for t in (0.0, 20 / 3, 40 / 3, 20.0)]
    assert all(len(ax.patches) >= 2 * 3 for ax in fig.axes)   # target, tube, body per robot
    assert "closest approach in the run" in fig._suptitle.get_text()
    for bad in (0, MAX_SLICES + 1, 2.5, True):
        with pytest.raises(SpecError, match="slices"):
            fleet_figure(designed, slices=bad)
    assert stt.plot_fleet(designed, tmp_path / "f.png").stat().st_size > 10_000
