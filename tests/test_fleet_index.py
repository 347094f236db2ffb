"""The space-time index of placed tubes (stt_codegen.design.fleet_index): chunks that hold
the enclosure, and queries that find exactly the robots whose boxes meet the query's."""

from __future__ import annotations

import numpy as np
import pytest

from stt_codegen.design.fleet_index import Chunks, TubeIndex, chunks


class _Boxes:
    """A stand-in for a RobotTube: ``boxes(dims)`` over a fixed partition."""

    def __init__(self, t0, t1, lo, hi):
        self.t0, self.t1 = np.asarray(t0, float), np.asarray(t1, float)
        self.lo, self.hi = np.asarray(lo, float), np.asarray(hi, float)

    def boxes(self, dims):
        return self.t0, self.t1, self.lo[:, list(dims)], self.hi[:, list(dims)]


def _moving_tube(count=40, dt=0.1):
    """A unit-width box sliding along x at 1 m/s over ``count`` intervals, then parked."""
    t0 = np.arange(count + 1) * dt
    t1 = np.append(t0[1:], np.inf)
    x = np.append(np.arange(count) * dt, count * dt)
    lo = np.stack([x, np.zeros_like(x)], axis=1)
    return _Boxes(t0, t1, lo, lo + 1.0)


def _chunk(t0, t1, lo, hi):
    return Chunks(np.array([t0], float), np.array([t1], float), np.array([lo], float),
                  np.array([hi], float))


def test_chunks_hold_every_box_of_the_enclosure_over_at_most_the_span():
    tube = _moving_tube()
    c = chunks(tube, (0, 1), 0.5)
    assert c.t_start[0] == 0.0 and c.t_end[-1] == np.inf
    assert np.array_equal(c.t_end[:-1], c.t_start[1:])
    assert np.all(c.t_end[:-1] - c.t_start[:-1] <= 0.5 + 1e-9)
    assert c.t_start.size < tube.t0.size                 # merged, not copied
    for k in range(tube.t0.size):                        # every box inside its chunk
        j = np.searchsorted(c.t_start, tube.t0[k], side="right") - 1
        assert c.t_end[j] >= tube.t1[k]
        assert np.all(c.lower[j] <= tube.lo[k]) and np.all(c.upper[j] >= tube.hi[k])


def test_chunks_keep_dims_and_a_long_interval_whole():
    tube = _Boxes([0.0, 5.0], [5.0, np.inf], [[0, 1, 2], [3, 4, 5]], [[1, 2, 3], [4, 5, 6]])
    c = chunks(tube, (2, 0), 1.0)
    assert c.lower.shape == (2, 2)
    assert c.lower[0].tolist() == [2.0, 0.0] and c.upper[1].tolist() == [6.0, 4.0]


def test_meets_needs_a_common_time_unless_untimed_and_grows_both_ways():
    a = _chunk(0.0, 1.0, [0, 0], [1, 1])
    later = _chunk(2.0, 3.0, [0.5, 0.5], [2, 2])
    assert not a.meets(later, 0.0) and a.meets(later, 0.0, timed=False)
    beside = _chunk(0.5, 1.5, [1.3, 0.0], [2, 1])            # 0.3 to the right
    assert not a.meets(beside, 0.2) and a.meets(beside, 0.31)
    left = _chunk(0.5, 1.5, [-2, 0.0], [-0.3, 1])            # 0.3 to the left
    assert not a.meets(left, 0.2) and a.meets(left, 0.31)


def test_near_finds_exactly_the_robots_brute_force_finds():
    rng = np.random.default_rng(7)
    index = TubeIndex(2.0)
    placed = {}
    for r in range(60):
        k = 6
        t0 = np.sort(rng.uniform(0, 20, k))
        t0[0] = 0.0
        t1 = np.append(t0[1:], np.inf)
        lo = rng.uniform(0, 30, (k, 2))
        hi = lo + rng.uniform(0.2, 3.0, (k, 2))
        placed[f"r{r}"] = Chunks(t0, t1, lo, hi)
        index.add(f"r{r}", placed[f"r{r}"])
    assert len(index) == 60
    for q in range(20):
        lo = rng.uniform(0, 30, (4, 2))
        t0 = np.sort(rng.uniform(0, 20, 4))
        query = Chunks(t0, t0 + rng.uniform(0.5, 3, 4), lo, lo + 1.0)
        for timed in (True, False):
            brute = sorted(n for n, c in placed.items() if query.meets(c, 0.4, timed))
            assert index.near(query, 0.4, timed) == brute
    # the random draw is not degenerate: some queries find robots, none finds them all
    found = [len(index.near(Chunks(np.zeros(1), np.ones(1), np.full((1, 2), x),
                                   np.full((1, 2), x + 1)), 0.4, False)) for x in (5, 15, 25)]
    assert 0 < max(found) < 60


def test_near_reads_only_the_buckets_it_meets():
    index = TubeIndex(1.0)
    far = _chunk(0.0, np.inf, [50, 50], [51, 51])
    index.add("far", far)
    index.add("close", _chunk(0.0, np.inf, [0, 0], [1, 1]))
    assert index.near(_chunk(0.0, 1.0, [1.2, 0], [2, 1]), 0.3) == ["close"]
    assert index.near(_chunk(0.0, 1.0, [1.2, 0], [2, 1]), 0.1) == []
    # a query without finite bounds is compared with every robot
    unbounded = _chunk(0.0, 1.0, [-np.inf, -np.inf], [np.inf, np.inf])
    assert index.near(unbounded, 0.0) == ["close", "far"]


def test_index_refuses_a_cell_that_is_not_positive():
    with pytest.raises(ValueError, match="cell"):
        TubeIndex(0.0)
