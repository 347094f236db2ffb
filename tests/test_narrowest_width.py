"""The certified narrowest width, the gain of law (13) comes from: sound, and tight.

Sound: a lower bound of the deployed tube's width at every ``t`` (the controller's own
``alpha`` steps, interpolated between samples). Tight: within 20 % of the width densely
sampled (every sampling instant and eight points in every period), on the bundled cases,
on the issue's three new-user tasks (tests/specs) and on 50 seeded via-point designs.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest
from conftest import CASES, designed

from stt_codegen.rounding import round_down
from stt_codegen_bench.arenas import arena_spec
from stt_codegen.design.certificate import (certify_tube, enclose, piece_ranges,
                                            sequence_bounds)
from stt_codegen.design.certificate.enclosures import width_lower_bound
from stt_codegen.design.samples import sample_tube
from stt_codegen.design.search import design_tube
from stt_codegen.errors import DesignError
from stt_codegen.spec.loader import load_spec
from stt_codegen.tube import reference as R

SPECS = Path(__file__).parent / "specs"
#: The issue's new-user tasks, on via points.
ISSUE_SPECS = ["warehouse-shelves.toml", "wall-gap-s1.toml", "skewed-linear-via.toml"]
#: Certified / densely sampled narrowest width, at least.
TIGHT = 0.8
VIA_DESIGNS = 50


def deployed_widths(design, per_period: int = 8, extra: int = 20_000, seed: int = 0):
    """``(t, alpha, gamma_U - gamma_L)`` of the deployed tube: every sampling instant,
    ``per_period`` points in each period and ``extra`` random times, on ``[0, 1.2 t_c]``,
    ``alpha`` linearly interpolated between the controller's steps."""
    samples = sample_tube(design, 1.2 * design.prescribed_time)
    frac = np.arange(per_period) / per_period
    t = (samples.t[:-1, None] + (samples.t[1:] - samples.t[:-1])[:, None] * frac).ravel()
    t = np.concatenate([t, samples.t[-1:],
                        np.random.default_rng(seed).uniform(0.0, samples.t[-1], extra)])
    k = np.minimum(np.searchsorted(samples.t, t, side="right") - 1, samples.t.size - 2)
    f = ((t - samples.t[k]) / (samples.t[k + 1] - samples.t[k]))[:, None]
    alpha = (1 - f) * samples.alpha[k] + f * samples.alpha[k + 1]
    with R.numpy_math():
        g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    return t, alpha, g_u - g_l


def check_sound_and_tight(design, certificate) -> float:
    """Assert the certificate's narrowest width is a lower bound of the deployed width
    (and its per-interval bounds too) and within :data:`TIGHT` of the sampled minimum;
    return certified / sampled."""
    t, _, width = deployed_widths(design)
    enc = certificate.enclosure
    j = np.searchsorted(enc.t_start, t, side="right") - 1
    assert np.all(enc.width_min[j] <= width + 1e-12)
    sampled = float(width.min())
    assert certificate.min_width <= sampled + 1e-12
    # the gains' width is the non-empty margin rounded down, the same on every CPU
    assert certificate.min_width == round_down(certificate.margin("non-empty").margin)
    ratio = certificate.min_width / sampled
    assert ratio >= TIGHT, (design.name, certificate.min_width, sampled)
    return ratio


def test_bundled_cases_width_is_sound_and_tight(case):
    _, design, check = designed(case)
    check_sound_and_tight(design, check.certificate)


@pytest.mark.parametrize("name", ISSUE_SPECS)
def test_issue_tasks_width_is_sound_and_tight(name):
    """Via-point tasks where a loose bound of the width was 6 to 16 times below the
    deployed width (0.033 for 0.2, 0.015 for 0.1, 0.013 for 0.2)."""
    found = design_tube(load_spec(SPECS / name))
    assert found.method == "via"
    assert check_sound_and_tight(found.tube, found.certificate) >= 0.95


@lru_cache(maxsize=None)
def via_designs() -> tuple:
    """The first :data:`VIA_DESIGNS` random arenas of seed 20 (bench.arenas) that have a
    via-point design, with ``tube.method = "via"``."""
    out = []
    index = 0
    while len(out) < VIA_DESIGNS:
        spec = arena_spec("paper", 20, index)
        spec = dataclasses.replace(spec, tube=dataclasses.replace(spec.tube, method="via"))
        index += 1
        try:
            out.append(design_tube(spec))
        except DesignError:
            continue
    return tuple(out)


@pytest.mark.slow
def test_fifty_seeded_via_designs_width_is_sound_and_tight():
    ratios = [check_sound_and_tight(d.tube, d.certificate) for d in via_designs()]
    assert len(ratios) == VIA_DESIGNS and min(ratios) >= TIGHT


def test_a_moving_box_keeps_its_width():
    """On a via segment the reach box moves metres in one interval; the difference of the
    bounds' ranges loses all of it, the width bound of eq. (10)'s exact decomposition
    none of it."""
    found = design_tube(load_spec(SPECS / "warehouse-shelves.toml"))
    design = found.tube
    seg = design.segments[len(design.segments) // 2]
    t0, t1 = np.array([seg.start]), np.array([seg.end])
    with R.numpy_math():
        pieces = piece_ranges(design, t0, t1)
        alpha = np.zeros((1, 2 * design.dimension))
        enc = enclose(design, pieces, alpha, alpha, t0, t1)
        direct = width_lower_bound(design, pieces, alpha)
    assert float((enc.upper_min - enc.lower_max).min()) < 0.0         # the old bound
    box = np.array(seg.upper_to) - np.array(seg.lower_to)
    assert np.all(direct >= box - 0.02)                                # the box's own width
    assert np.all(enc.width_min == np.maximum(enc.upper_min - enc.lower_max, direct))
    # and it is a lower bound of the width along the segment (alpha at its lower bound 0)
    t = np.linspace(seg.start, seg.end, 2001)
    with R.numpy_math():
        g_l, g_u, _, _ = R.adaptive_tube(design, t, np.zeros((t.size, 2 * design.dimension)))
    assert np.all(direct[0] <= (g_u - g_l).min(axis=0) + 1e-12)


@pytest.mark.parametrize("name", CASES)
def test_alpha_inside_an_interval_is_bounded_by_its_sequences(name):
    """SequenceBounds.within: the deployed alpha at every step of a long interval lies in
    the bounds over any window of its steps."""
    spec, design, check = designed(name)
    cert = certify_tube(design, spec)
    enc, state = cert.enclosure, cert.state
    samples = sample_tube(design, 1.2 * design.prescribed_time)
    steps = np.diff(np.array(state.points, dtype=float))
    rows = np.flatnonzero(steps >= 20)[:40]
    entry_lo = np.array([state.entries[k][0] for k in rows])
    entry_hi = np.array([state.entries[k][1] for k in rows])
    with R.numpy_math():
        inside = sequence_bounds(design, enc.psi_min[rows], enc.psi_max[rows], entry_lo,
                                 entry_hi)
    tighter = 0
    for slot, k in enumerate(rows):
        start, count = state.points[k], int(steps[k])
        actual = samples.alpha[start:start + count + 1]
        for j0, j1 in ((0, count), (0, count // 3), (count // 3, count // 2),
                       (count - 1, count)):
            lo, hi = inside.within(np.array([slot]), np.array([float(j0)]),
                                   np.array([float(j1)]))
            window = actual[j0:j1 + 1]
            assert np.all(lo[0] - 1e-12 <= window.min(axis=0)), (name, k, j0, j1)
            assert np.all(window.max(axis=0) <= hi[0] + 1e-12), (name, k, j0, j1)
            tighter += int(np.any(lo[0] > enc.alpha_min[k] + 1e-9)
                           or np.any(hi[0] < enc.alpha_max[k] - 1e-9))
    assert tighter > 0        # and the windows are tighter than the interval's range


def test_sharpening_cuts_the_partition_only_where_the_width_needs_it():
    """The proof's partition is cut again only after every property holds, and the bounds
    are propagated again only around the cuts (Certificate.work counts them)."""
    spec = load_spec("omnirobot-s1")
    _, design, _ = designed("omnirobot-s1")
    plain = certify_tube(design, spec, final=False)       # no width sharpening
    sharp = certify_tube(design, spec)
    assert sharp.passed and plain.passed
    assert sharp.intervals >= plain.intervals
    assert sharp.min_width > 1.1 * float(plain.enclosure.width_min.min())
    # far less work than propagating the whole sharpened partition once more
    assert sharp.work < plain.work + sharp.intervals
