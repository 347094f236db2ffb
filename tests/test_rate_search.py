"""The upward rate search of the cascade's design (stt_codegen/design/cascade_gain.py,
``upward_search``): doublings from the failing rate, then a bisection on the two-digit grid
(stt_codegen/design/grid.py) between the last doubling that failed and the first that passed."""

from __future__ import annotations

import pytest

from stt_codegen.design.cascade_gain import upward_search
from stt_codegen.design.grid import grid_index, grid_value


@pytest.mark.parametrize("threshold", [120.0, 510.0, 650.0, 999.0, 1000.0, 3900.0, 7900.0])
def test_it_finds_the_smallest_passing_grid_rate_trying_slow_rates_first(threshold):
    tried = []

    def passes(index):
        tried.append(grid_value(index))
        return grid_value(index) >= threshold

    found = upward_search(passes, 100.0, 8000.0)
    smallest = min(grid_value(j) for j in range(grid_index(100.0) + 1, grid_index(8000.0) + 1)
                   if grid_value(j) >= threshold)
    assert grid_value(found) == smallest
    # no rate faster than twice the answer is ever tried: a faster certificate is dearer
    assert max(tried) <= max(2.0 * smallest, grid_value(grid_index(200.0)))
    assert len(tried) <= 16


def test_none_when_no_rate_up_to_the_fastest_passes():
    tried = []
    assert upward_search(lambda j: tried.append(grid_value(j)) or False, 100.0, 900.0) is None
    assert max(tried) <= 900.0 and tried == sorted(tried)
    assert upward_search(lambda j: True, 100.0, 100.0) is None     # nothing above the rate
