"""The certificate's faster paths give the numbers of the plain ones, to the last bit.

``Propagation`` keeps its coefficients as one nested list and iterates them per
component; here its bounds are compared with a transcription of the plain propagation
(coefficient lists indexed one by one) on drawn partitions, start bounds and tube
parameters. ``smooth_max_pair`` is compared with ``smooth_max`` of the stacked values, and
``piece_ranges`` (each bump's ranges computed once) with ``circumvent_range`` computing its
own; ``reach_tube`` (one evaluation over its segments) with a segment-by-segment one, and
the other shortcuts of the design (the rates left out where unused, ``nan_to_num`` without
its wrapper, the tracking demand's errors in one broadcast) with the plain forms.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math

import numpy as np
import pytest
from conftest import CASES, designed
from hypothesis import given, settings
from hypothesis import strategies as st

from stt_codegen.design.certificate import enclosures
from stt_codegen.design.certificate import (EXACT_STEPS, alpha_fixed_point,
                                            alpha_ranges, circumvent_range, piece_ranges,
                                            step_psi, step_root)
from stt_codegen.design.search import base_design
from stt_codegen.design.via import via_design
from stt_codegen.tube import reference


def _plain_coefficients(design, psi_lo, psi_hi, steps):
    """The coefficients of the propagation, computed as the plain propagation does."""
    kappa, dt = design.kappa, 1.0 / design.rate_hz
    c = 1.0 + kappa * dt
    theta_hi = reference.trigger(design, psi_lo)
    theta_lo = reference.trigger(design, psi_hi)
    star_hi, star_lo = np.zeros_like(psi_lo), np.zeros_like(psi_hi)
    long = steps > EXACT_STEPS
    if long.any():
        # lower ends for (psi_hi, theta_lo) and upper ends for (psi_lo, theta_hi), one call
        lo, hi = alpha_fixed_point(np.concatenate([psi_hi[long], psi_lo[long]]),
                                   np.concatenate([theta_lo[long], theta_hi[long]]), kappa)
        half = int(long.sum())
        star_lo[long], star_hi[long] = lo[:half], hi[half:]
    with np.errstate(divide="ignore", over="ignore", under="ignore", invalid="ignore"):
        q_lo = 1.0 / (c + 2.0 * dt * theta_lo / (psi_hi + star_lo) ** 3)
        decay_lo = np.where(np.isinf(steps)[:, None], 0.0,
                            np.power(q_lo, np.minimum(steps, 1e300)[:, None]))
    decay_lo = np.where(np.isnan(decay_lo), 1.0, decay_lo)
    return (kappa, dt, c, star_lo.tolist(), star_hi.tolist(), decay_lo.tolist(), steps.tolist(),
            psi_lo.tolist(), psi_hi.tolist(), theta_lo.tolist(), theta_hi.tolist())


def _plain_alpha_ranges(design, psi_lo, psi_hi, steps, start, own_psi):
    """alpha_ranges written plainly: every coefficient indexed ``[k][i]``."""
    (kappa, dt, c, s_lo, s_hi, d_lo_all, steps_l, p_lo_all, p_hi_all, t_lo_all,
     t_hi_all) = _plain_coefficients(design, psi_lo, psi_hi, steps)
    m = psi_lo.shape[1]
    a_lo, a_hi = list(start[0]), list(start[1])
    out_lo, out_hi, entries = [], [], []
    for k, steps_k in enumerate(steps_l):
        entries.append((list(a_lo), list(a_hi)))
        sl, sh = s_lo[k], s_hi[k]
        p_lo, p_hi, t_lo, t_hi = p_lo_all[k], p_hi_all[k], t_lo_all[k], t_hi_all[k]
        row_lo, row_hi = [0.0] * m, [0.0] * m
        if steps_k <= EXACT_STEPS:
            own = None if own_psi is None else own_psi[k]
            for i in range(m):
                lo_i, hi_i = a_lo[i], a_hi[i]
                low, high = lo_i, hi_i
                for j in range(int(steps_k)):
                    if own is None:
                        psi_l, psi_h, th_l, th_h = p_lo[i], p_hi[i], t_lo[i], t_hi[i]
                    else:
                        psi_l, psi_h = own[0][j][i], own[1][j][i]
                        th_l, th_h = own[2][j][i], own[3][j][i]
                    lo_i = max(step_root(lo_i, psi_h, th_l, dt, c)[0], 0.0)
                    hi_i = step_root(hi_i, psi_l, th_h, dt, c)[1]
                    low, high = min(low, lo_i), max(high, hi_i)
                row_lo[i], row_hi[i], a_lo[i], a_hi[i] = low, high, lo_i, hi_i
        elif math.isinf(steps_k):
            for i in range(m):
                row_lo[i] = min(a_lo[i], sl[i])
                row_hi[i] = max(a_hi[i], sh[i])
        else:
            span = steps_k * dt
            c_span = 1.0 + kappa * span
            d_lo = d_lo_all[k]
            for i in range(m):
                lo_i, hi_i = a_lo[i], a_hi[i]
                if lo_i <= sl[i]:
                    end = max(step_root(lo_i, p_hi[i], t_lo[i], span, c_span)[0],
                              sl[i] - (sl[i] - lo_i) * d_lo[i])
                    row_lo[i] = lo_i
                else:
                    z = p_hi[i] + lo_i
                    end = sl[i] if not z > 0.0 else max(
                        sl[i], lo_i + span * (t_lo[i] / (z * z) - kappa * lo_i))
                    row_lo[i] = end
                a_lo[i] = end if end > 0.0 else 0.0
                if hi_i >= sh[i]:
                    q = 1.0 / (c + 2.0 * dt * t_hi[i] / (p_lo[i] + hi_i) ** 3)
                    end = min(step_root(hi_i, p_lo[i], t_hi[i], span, c_span)[1],
                              sh[i] + (hi_i - sh[i]) * q ** steps_k)
                    row_hi[i] = hi_i
                else:
                    z = p_lo[i] + hi_i
                    end = sh[i] if not z > 0.0 else min(
                        sh[i], hi_i + span * (t_hi[i] / (z * z) - kappa * hi_i))
                    row_hi[i] = end
                a_hi[i] = end
        out_lo.append(row_lo)
        out_hi.append(row_hi)
    return out_lo, out_hi, entries


@st.composite
def _partitions(draw):
    """A bundled tube with drawn kappa and theta0, a drawn partition of its samples (short
    and long intervals, the tail) and drawn bounds of alpha at its start."""
    tube = designed(draw(st.sampled_from(CASES)))[1]
    tube = dataclasses.replace(tube, kappa=tube.kappa * draw(st.floats(0.2, 5.0)),
                               theta0=tube.theta0 * draw(st.floats(0.2, 5.0)))
    end = int(math.ceil(tube.prescribed_time * tube.rate_hz)) + 1
    cuts = draw(st.lists(st.integers(1, end - 1), min_size=1, max_size=30))
    # runs of single steps, where the short intervals follow each step
    runs = [p + q for p in draw(st.lists(st.integers(1, end - 6), min_size=1, max_size=4)) for q in range(5)]
    points = sorted({0, end, *cuts, *runs})
    m = 2 * tube.dimension
    lo = draw(st.lists(st.floats(0.0, 0.5), min_size=m, max_size=m))
    widen = draw(st.lists(st.floats(0.0, 0.5), min_size=m, max_size=m))
    own = draw(st.booleans())
    return tube, points, (lo, [a + b for a, b in zip(lo, widen)]), own


@settings(max_examples=60, deadline=None)
@given(_partitions())
def test_propagation_is_the_plain_propagation_to_the_last_bit(drawn):
    """alpha_ranges (and so every advance) gives the plain transcription's bounds exactly,
    with each short step's own psi and with the interval's range."""
    tube, points, start, own = drawn
    dt = 1.0 / tube.rate_hz
    i0 = np.array(points)
    i1 = np.append(i0[1:], -1)
    steps = np.where(i1 < 0, np.inf, (i1 - i0).astype(float))
    t0 = i0 * dt
    with reference.numpy_math():
        pieces = piece_ranges(tube, t0, np.where(i1 < 0, t0, i1 * dt))
        own_psi = step_psi(tube, i0, steps) if own else None
        fast = alpha_ranges(tube, pieces.psi_lo, pieces.psi_hi, steps, start, own_psi)
        plain = _plain_alpha_ranges(tube, pieces.psi_lo, pieces.psi_hi, steps, start, own_psi)
    assert (steps <= EXACT_STEPS).any() and (steps > EXACT_STEPS).any()
    assert fast == plain


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=1, max_size=20),
       st.floats(0.1, 200.0), st.booleans())
def test_smooth_max_pair_is_smooth_max_of_two(pairs, nu, fast_math):
    """The two-value smooth max is smooth_max's value of the stacked pair, bit for bit,
    with libm and with numpy's kernels."""
    values = np.array(pairs)
    a, b = values[:, 0].copy(), values[:, 1].copy()
    with reference.numpy_math() if fast_math else contextlib.nullcontext():
        pair = reference.smooth_max_pair(a, b, nu)
        full = reference.smooth_max(values, nu)[0]
    assert np.array_equal(pair, full)


def test_piece_ranges_beta_is_circumvent_range():
    """The beta ranges of piece_ranges (bumps shared with the rates) are circumvent_range's."""
    for name in CASES:
        tube = designed(name)[1]
        assert tube.circumvents
        t = np.linspace(0.0, tube.prescribed_time, 97)
        with reference.numpy_math():
            pieces = piece_ranges(tube, t[:-1], t[1:])
            beta_l, beta_u = circumvent_range(tube, t[:-1], t[1:])
        for got, want in zip(pieces.beta_l + pieces.beta_u, beta_l + beta_u):
            assert np.array_equal(got, want)


def _plain_reach_tube(design, t):
    """reach_tube written plainly: segment by segment (segment_progress on the points in
    it), the bounds' arrays built from the segment's tuples."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    segments = design.segments
    ends = np.array([seg.end for seg in segments])
    which = np.minimum(np.searchsorted(ends, t, side="right"), len(segments) - 1)
    out = [np.zeros((t.size, design.dimension)) for _ in range(4)]
    for k, seg in enumerate(segments):
        here = which == k
        if not here.any():
            continue
        s, s_dot = reference.segment_progress(seg, t[here])
        for pair, (a, b) in enumerate(((seg.lower_from, seg.lower_to),
                                       (seg.upper_from, seg.upper_to))):
            a, b = np.array(a), np.array(b)
            out[pair][here] = (b - a) * s[:, None] + a
            out[pair + 2][here] = (b - a) * s_dot[:, None]
    return out


@pytest.mark.parametrize("profiles", [("tanh",), ("smoothstep",), ("cruise",), ("scurve",),
                                      ("glide",), ("tanh", "smoothstep", "cruise", "scurve",
                                                   "glide")])
@pytest.mark.parametrize("fast_math", [False, True])
def test_reach_tube_is_the_plain_segment_by_segment_one(profiles, fast_math):
    """reach_tube (each point with its own segment's start and end in one evaluation, the
    bounds' arrays built once) gives the plain segment-by-segment numbers to the bit, with
    and without the rates, for one profile and for mixed ones."""
    from stt_codegen_bench.arenas import arena_spec
    spec = arena_spec("paper", 0, 11)
    via = via_design(spec, base_design(spec))
    assert len(via.segments) >= 3
    segments = tuple(dataclasses.replace(seg, profile=profiles[k % len(profiles)])
                     for k, seg in enumerate(via.segments))
    tube = dataclasses.replace(via, segments=segments)
    edges = [seg.start for seg in segments] + [seg.end for seg in segments]
    t = np.concatenate([np.linspace(-1.0, tube.prescribed_time + 1.0, 501), edges,
                        np.nextafter(edges, np.inf), np.nextafter(edges, -np.inf)])
    with reference.numpy_math() if fast_math else contextlib.nullcontext():
        plain = _plain_reach_tube(tube, t)
        fast = reference.reach_tube(tube, t)
        values = reference.reach_tube(tube, t, rates=False)
        if len(segments) > 1:
            one = dataclasses.replace(tube, segments=segments[:1])
            plain_one, fast_one = _plain_reach_tube(one, t), reference.reach_tube(one, t)
    for got, want in zip(fast, plain):
        assert got.tobytes() == want.tobytes()
    assert values[0].tobytes() == plain[0].tobytes() and values[1].tobytes() == plain[1].tobytes()
    assert values[2] is None and values[3] is None
    for got, want in zip(fast_one, plain_one):
        assert got.tobytes() == want.tobytes()


@pytest.mark.parametrize("fast_math", [False, True])
def test_segments_progress_is_each_segment_on_its_own_row(fast_math):
    """segments_progress (one evaluation per profile) gives each segment's segment_progress
    on its own row to the bit: mixed profiles, times before, inside and after each segment."""
    from stt_codegen_bench.arenas import arena_spec
    spec = arena_spec("paper", 0, 11)
    via = via_design(spec, base_design(spec))
    rng = np.random.default_rng(3)
    for profiles in (("tanh",), ("smoothstep", "cruise", "scurve", "glide"),
                     ("tanh", "smoothstep", "cruise", "scurve", "glide")):
        segments = [dataclasses.replace(seg, profile=profiles[k % len(profiles)])
                    for k, seg in enumerate(via.segments)]
        t = np.array([np.linspace(seg.start - 1.0, seg.end + 1.0, 13) for seg in segments])
        t += rng.normal(0.0, 0.3, t.shape)
        with reference.numpy_math() if fast_math else contextlib.nullcontext():
            want = np.array([reference.segment_progress(seg, row)[0]
                             for seg, row in zip(segments, t)])
            got = reference.segments_progress(segments, t)
        assert got.tobytes() == want.tobytes()
        assert np.any(got == 0.0) and np.any(got == 1.0) and np.any((got > 0) & (got < 1))


def _dense_reach_range(tube, t0, t1, rates):
    """reach_range's ranges written densely: the tube at both ends of every interval and at
    every segment edge (and, for the rates, peak) clipped into every interval."""
    segments = tube.segments
    edges = sorted({s.start for s in segments} | {s.end for s in segments})
    w = enclosures._W_STAR
    peaks = [s.start + s.duration * (w / (1.0 + w) if s.profile == "tanh" else 0.5)
             for s in segments]
    values = [t0, t1] + [np.minimum(np.maximum(e, t0), t1) for e in edges]
    rates_at = values + [np.minimum(np.maximum(p, t0), t1) for p in peaks]
    rho = [reference.reach_tube(tube, t) for t in values]
    lower = np.array([r[0] for r in rho])
    upper = np.array([r[1] for r in rho])
    out = [(lower.min(0), lower.max(0)), (upper.min(0), upper.max(0))]
    if rates:
        at_ends = np.zeros(t0.shape, dtype=bool)
        for seg in segments:
            at_ends |= (t0 < seg.end) & (seg.end <= t1)
        zero = np.where(at_ends[:, None], 0.0, np.nan)
        r = [reference.reach_tube(tube, t) for t in rates_at]
        spans = []
        for j in (2, 3):
            a = np.array([x[j] for x in r])
            spans.append((np.fmin(a.min(0), zero), np.fmax(a.max(0), zero)))
        out.append(tuple(spans))
    else:
        out.append(None)
    out.append((upper - lower).min(0))
    return out


@pytest.mark.parametrize("rates", [True, False])
def test_reach_range_is_the_dense_range_over_every_edge(rates):
    """reach_range (each interval's ends and only the edges and peaks inside it) gives the
    ranges of the tube at both ends and every edge and peak clipped into every interval, to
    the bit: partitions whose points fall on edges, between them and outside the tube's
    time."""
    from stt_codegen_bench.arenas import arena_spec
    spec = arena_spec("paper", 0, 11)
    via = via_design(spec, base_design(spec))
    rng = np.random.default_rng(5)
    edges = [seg.start for seg in via.segments] + [via.segments[-1].end]
    for profiles in (("tanh",), ("smoothstep", "cruise", "scurve", "glide", "tanh")):
        tube = dataclasses.replace(via, segments=tuple(
            dataclasses.replace(seg, profile=profiles[k % len(profiles)])
            for k, seg in enumerate(via.segments)))
        for points in (np.sort(rng.uniform(-1.0, tube.prescribed_time + 2.0, 40)),
                       np.array(edges), np.sort(np.concatenate([edges, rng.uniform(0, 5, 7)])),
                       np.array([-1.0, tube.prescribed_time + 3.0]),
                       np.linspace(0.1, tube.prescribed_time - 0.1, 4)):
            t0, t1 = points[:-1], points[1:]
            got = enclosures.reach_range(tube, t0, t1, rates)
            want = _dense_reach_range(tube, t0, t1, rates)
            flat = lambda x: [a for v in x for a in (flat(v) if isinstance(v, tuple) else [v])]
            pairs = list(zip(flat(tuple(got)), flat(tuple(want))))
            assert len(pairs) == (9 if rates else 6)
            for a, b in pairs:
                assert (a is None and b is None) or a.tobytes() == b.tobytes()


def test_circumvent_without_rates_is_its_values():
    """circumvent(rates=False) (no weights, no rates) gives circumvent's beta to the bit."""
    for name in CASES:
        tube = designed(name)[1]
        t = np.linspace(0.0, tube.prescribed_time, 301)
        with reference.numpy_math():
            full = reference.circumvent(tube, t)
            values = reference.circumvent(tube, t, rates=False)
        assert values[0].tobytes() == full[0].tobytes()
        assert values[1].tobytes() == full[1].tobytes()


def test_sequence_bounds_map_nan_and_infinities_as_nan_to_num():
    """SequenceBounds.within's replacement of numpy.nan_to_num, on every special value."""
    from stt_codegen.design.certificate.implicit_step import _nan_to
    values = np.array([np.nan, np.inf, -np.inf, -0.0, 0.0, 1.5, -2e308, 5e-324,
                       np.finfo(float).max, -np.finfo(float).max])
    for nan in (np.inf, -np.inf):
        assert _nan_to(values, nan).tobytes() == np.nan_to_num(values, nan=nan).tobytes()


def test_tracking_demand_is_the_least_speed_over_each_error():
    """tracking_demand's least speed over the errors e (one broadcast) is the plain loop's."""
    from stt_codegen.design import tracking
    for name in CASES:
        spec, tube, check = designed(name)
        t, g_l, g_u, rate_l, rate_u = tracking._evaluate_partition(tube, check.certificate)
        speed = np.full(g_l.shape, np.inf)
        for e in tracking._ERRORS:
            speed = np.minimum(speed, np.abs((1.0 + e) * rate_u + (1.0 - e) * rate_l) / 2.0)
        a = spec.assumptions
        need = speed + a.disturbance_bound
        e = tracking.TRACKING_ERROR
        phi = math.log((1.0 + e) / (1.0 - e)) / (1.0 - e * e)
        ratio = need * (g_u - g_l) / (4.0 * phi * 0.5 * (a.input_gain[0] + a.input_gain[1])
                                      * tube.gain)
        k, i = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
        demand = tracking.tracking_demand(tube, check.certificate, spec)
        assert (demand.ratio, demand.time, demand.dimension) == (float(ratio[k, i]),
                                                                 float(t[k]), int(i))
