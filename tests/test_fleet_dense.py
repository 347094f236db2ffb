"""An independent dense check of the bundled fleet (docs/fleets.md): each robot's tube
evaluated by its own generated C on a fine time grid, and each robot's closed loop run
with its generated C; no two tubes grown by both reaches meet, and no two bodies do."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.runtime.compiled import build_shared

#: Sub-steps of the finest sampling period on the check's grid.
SUBSTEPS = 4


class GeneratedTube:
    """A robot's tube as its generated C computes it: ``P_alpha_step`` at its sampling
    instants from ``alpha = 0``, ``P_tube`` at any ``t`` with the ``alpha`` held since the
    last instant (what the deployed controller holds)."""

    def __init__(self, folder, name: str, rate_hz: float, n: int):
        sources = {p.name: p.read_bytes() for p in folder.iterdir()
                   if p.suffix in (".c", ".h") and "selftest" not in p.name}
        lib = ctypes.CDLL(str(build_shared(sources, f"{name}.c")))
        ptr = ctypes.POINTER(ctypes.c_double)
        self.tube = getattr(lib, f"{name}_tube")
        self.tube.argtypes = [ctypes.c_double] + [ptr] * 5
        self.alpha_step = getattr(lib, f"{name}_alpha_step")
        self.alpha_step.argtypes = [ctypes.c_double, ctypes.c_double, ptr, ptr]
        self.rate_hz, self.n, self.ptr = rate_hz, n, ptr

    def _p(self, a: np.ndarray):
        return a.ctypes.data_as(self.ptr)

    def boxes(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``gamma_L``, ``gamma_U`` (len(t), n) at increasing times ``t``."""
        dt = 1.0 / self.rate_hz
        n = self.n
        alpha, nxt = np.zeros(2 * n), np.zeros(2 * n)
        lo, hi, dlo, dhi = (np.zeros(n) for _ in range(4))
        out_lo, out_hi = np.empty((t.size, n)), np.empty((t.size, n))
        k = 0                                    # alpha is alpha_k on [k dt, (k + 1) dt)
        for i, ti in enumerate(t):
            while (k + 1) * dt <= ti + 1e-12:
                status = self.alpha_step(k * dt, dt, self._p(alpha), self._p(nxt))
                assert status == 0, (k, status)
                alpha[:] = nxt
                k += 1
            status = self.tube(float(ti), self._p(alpha), self._p(lo), self._p(hi),
                               self._p(dlo), self._p(dhi))
            assert status == 0, (ti, status)
            out_lo[i], out_hi[i] = lo, hi
        return out_lo, out_hi


def dense_gaps(designs, fleet, folder, t: np.ndarray) -> dict[tuple[str, str], np.ndarray]:
    """Per pair, at each ``t``, the largest gap along a body dimension between the two
    robots' tubes (each from its generated C in ``folder/<robot>``) grown by their reaches."""
    dims = list(fleet.robots[0].dims)
    boxes = {}
    for robot in fleet.robots:
        tube = GeneratedTube(folder / robot.name, designs[robot.name].spec.c_name,
                             robot.spec.rate_hz, robot.spec.dimension)
        lo, hi = tube.boxes(t)
        boxes[robot.name] = (lo[:, dims] - robot.reach, hi[:, dims] + robot.reach)
    gaps = {}
    for i, a in enumerate(fleet.robots):
        for b in fleet.robots[i + 1:]:
            (la, ua), (lb, ub) = boxes[a.name], boxes[b.name]
            gaps[a.name, b.name] = np.maximum(lb - ua, la - ub).max(axis=1)
    return gaps


@pytest.mark.slow
def test_no_two_robots_of_the_bundled_fleet_meet(tmp_path):
    designed = stt.design_fleet("warehouse-fleet")
    assert designed.certified
    fleet = designed.fleet
    written = stt.generate_fleet(designed, tmp_path / "fleet", languages="c")
    assert sorted(written) == sorted(r.name for r in fleet.robots)
    horizon = 1.25 * max(r.spec.prescribed_time for r in fleet.robots)
    finest = max(r.spec.rate_hz for r in fleet.robots)
    t = np.arange(0.0, horizon, 1.0 / (SUBSTEPS * finest))
    # every pair's tubes, each grown by its reach, apart along some dimension at every t
    gaps = dense_gaps(designed.designs, fleet, tmp_path / "fleet", t)
    for pair, gap in gaps.items():
        assert gap.min() > 0, (pair, float(t[np.argmin(gap)]))
    # the certificate's narrowest margin is a lower bound of what the dense grid sees
    assert designed.narrowest.margin <= min(g.min() for g in gaps.values()) + 1e-9
    # the control: the robots designed alone, each certified, do meet on the grid
    alone = {r.name: stt.design_tube(r.spec) for r in fleet.robots}
    (tmp_path / "alone").mkdir()
    for name, design in alone.items():
        stt.generate(design, tmp_path / "alone" / name, languages="c")
    met = [p for p, g in dense_gaps(alone, fleet, tmp_path / "alone", t).items()
           if g.min() <= 0]
    assert met
    # each robot's closed loop with its generated C: in its tube, its task met, and no two
    # bodies closer than their reaches at any common sampling instant
    run = stt.simulate_fleet(designed, backend="c", horizon=horizon)
    for name, result in run.results.items():
        assert result.satisfied and result.stayed_in_tube, name
    assert len(run.approaches) == 28
    assert run.closest.clearance > 0
    assert run.closest.clearance >= designed.narrowest.margin - 1e-9
