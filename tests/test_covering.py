"""Obstacles that are not boxes (Remark 3.1): covering by boxes, its guarantees, and use."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from conftest import arena_toml
from hypothesis import strategies as st

from stt_codegen.design.certificate import certify_tube
import stt_codegen.spec.covering as covering
from stt_codegen.spec.covering import MAX_BOXES, cover
from stt_codegen.design.search import design_tube
from stt_codegen.errors import SpecError
from stt_codegen.spec.shapes import Ball, make_polytope
from stt_codegen.runtime.simulate import simulate
from stt_codegen.spec.loader import load_spec, parse_spec

SPECS = Path(__file__).parent / "specs"
BESIDE = arena_toml("beside", extra="[tube]\ncircumvent_sharpness = 0.1\n",
                    target=((4.5, 0.0), (5.0, 0.5)))
BALL = "[[obstacles]]\ncenter = [1.0, 1.0]\nradius = 0.62\n"
START = (np.array([0.0, 0.0]), np.array([0.5, 0.5]))


def assert_valid_covering(shape, boxes, tolerance, forbidden, rng, inside_points):
    for lo, hi in boxes:
        for f_lo, f_hi in forbidden:        # Assumption 3, per box: misses X0 and T
            assert not (np.all(lo <= f_hi) and np.all(f_lo <= hi))
        corners = np.array(list(itertools.product(*zip(lo, hi))))
        worst = float(np.max(shape.distance(corners)))
        assert worst <= tolerance + 1e-12   # within the tolerance of the shape
    lows = np.array([b[0] for b in boxes])
    highs = np.array([b[1] for b in boxes])
    pts = inside_points(rng)
    covered = np.any(np.all((pts[:, None, :] >= lows - 1e-12) & (pts[:, None, :] <= highs + 1e-12),
                            axis=2), axis=1)
    assert covered.all()                     # the union contains the shape


@pytest.mark.slow
def test_ball_whose_bounding_box_meets_the_start_is_split_and_used():
    as_box = BESIDE + "[[obstacles]]\nlower = [0.38, 0.38]\nupper = [1.62, 1.62]\n"
    with pytest.raises(SpecError, match="meets the initial set"):
        parse_spec(as_box)                   # its bounding box violates Assumption 3
    spec = load_spec(SPECS / "ball-beside-start.toml")   # docs/spec-format.md's example
    assert spec.unsafe_sets[0].kind == "ball" and len(spec.obstacles) > 1
    rng = np.random.default_rng(0)
    ball = spec.unsafe_sets[0].shape

    def in_ball(r):
        d = r.normal(size=(4000, 2))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        return np.array(ball.center) + d * ball.radius * np.sqrt(r.random((4000, 1)))

    boxes = [(np.array(o.lower), np.array(o.upper)) for o in spec.obstacles]
    assert_valid_covering(ball, boxes, 0.05, [START, (np.array([4.5, 0.0]), np.array([5.0, 0.5]))],
                          rng, in_ball)
    found = design_tube(spec)
    assert found.check.passed
    result = simulate(found, backend="casadi")
    assert result.satisfied and result.min_obstacle_clearance > 0.1   # against the real ball


def test_certificate_margin_bounds_the_distance_to_the_real_shape():
    spec = parse_spec(BESIDE + BALL)
    design = design_tube(spec).tube
    cert = certify_tube(design, spec)
    margin = next(m for m in cert.margins if m.name == "avoids obstacle 0").margin
    enc = cert.enclosure
    ball = spec.unsafe_sets[0].shape
    c = np.array(ball.center)
    nearest = np.clip(c, enc.lower_min, enc.upper_max)
    distance = np.linalg.norm(nearest - c, axis=1) - ball.radius
    assert margin > 0 and distance.min() >= margin - 1e-12


@settings(max_examples=12, deadline=None)
@given(points=st.lists(st.tuples(st.floats(1.0, 4.0), st.floats(1.0, 4.0)), min_size=3,
                       max_size=8, unique=True),
       tolerance=st.sampled_from([0.1, 0.3]))
def test_random_polygons_are_covered_within_tolerance(points, tolerance):
    pts = np.array(points)
    if np.linalg.matrix_rank(pts[1:] - pts[0], tol=1e-3) < 2:
        return
    shape = make_polytope([list(p) for p in points], "obstacles[0]")
    forbidden = [START]
    boxes = cover(shape, tolerance, forbidden)
    rng = np.random.default_rng(1)

    def in_polygon(r):
        w = r.dirichlet(np.ones(len(points)), 3000)
        return w @ pts

    assert_valid_covering(shape, boxes, tolerance, forbidden, rng, in_polygon)
    again = cover(shape, tolerance, forbidden)          # deterministic
    assert len(again) == len(boxes) and all(
        np.array_equal(x[0], y[0]) and np.array_equal(x[1], y[1]) for x, y in zip(again, boxes))


def test_covering_is_deterministic():
    spec_a = parse_spec(BESIDE + BALL)
    spec_b = parse_spec(BESIDE + BALL)
    assert spec_a.obstacles == spec_b.obstacles


def test_a_shape_that_meets_the_start_cannot_be_covered():
    touching = BESIDE + "[[obstacles]]\ncenter = [0.9, 0.9]\nradius = 0.6\n"
    with pytest.raises(SpecError, match=r"obstacles\[0\]: meets the initial set"):
        parse_spec(touching)


def test_no_covering_within_the_box_budget_is_a_clear_error():
    # 1 micrometre from the start set's corner: boxes that miss it are too many
    close = BESIDE + ("[[obstacles]]\ncenter = [0.9, 0.9]\nradius = 0.565684\n"
                      "tolerance = 0.001\n")
    with pytest.raises(SpecError, match=rf"no covering by at most {MAX_BOXES} boxes"):
        parse_spec(close)


@pytest.mark.parametrize("table, field, reason", [
    ("center = [1.0, 1.0]\n", "obstacles[0].radius", "missing"),
    ("center = [1.0, 1.0]\nradius = -1.0\n", "obstacles[0].radius", "must be positive"),
    ("center = [1.0, 1.0]\nradius = 0.2\ntolerance = 0.0\n", "obstacles[0].tolerance",
     "must be positive"),
    ("center = [4.9, 4.0]\nradius = 0.2\n", "obstacles[0]", "not inside the state space"),
    ("vertices = [[1.0, 1.0], [2.0, 2.0]]\n", "obstacles[0].vertices", "at least 3"),
    ("vertices = [[1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]\n", "obstacles[0].vertices", "degenerate"),
    ("vertices = [[1.0, 1.0], [2.0, nan], [3.0, 1.0]]\n", "obstacles[0].vertices[1][1]",
     "finite"),
    ("vertices = 3\n", "obstacles[0].vertices", "array of points"),
    ("vertices = [[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]]\nradius = 1.0\n", "obstacles[0].radius",
     "unknown key"),
])
def test_bad_shapes_name_field_and_reason(table, field, reason):
    with pytest.raises(SpecError) as info:
        parse_spec(BESIDE + "[[obstacles]]\n" + table)
    assert info.value.field == field and reason in info.value.reason, str(info.value)


def test_too_close_to_the_start_names_the_start_set(monkeypatch):
    """A covering refused because the shape comes close to X0 blames X0 (and not T): with
    a budget of 20 boxes, the ball 1 micrometre from the start's corner needs 27 at
    tolerance 0.2 (before merging), 8 without the start set."""
    import stt_codegen.spec.covering as covering
    ball = Ball((0.9, 0.9), 0.565684)
    monkeypatch.setattr(covering, "MAX_BOXES", 20)
    assert cover(ball, 0.2, [])                         # fits without the start set
    with pytest.raises(SpecError) as info:
        parse_spec(BESIDE + "[[obstacles]]\ncenter = [0.9, 0.9]\nradius = 0.565684\n"
                            "tolerance = 0.2\n")
    assert info.value.field == "obstacles[0]"
    assert "misses the initial set" in info.value.reason, str(info.value)
    assert "target" not in info.value.reason


def test_a_tolerance_too_fine_for_the_shape_is_blamed_on_the_tolerance():
    """A quadrilateral in mid-arena, far from the start and the target, at
    tolerance 0.01 needs more than MAX_BOXES boxes; the message says so (it blamed the
    initial and target sets) and comes at once (it took seconds)."""
    quad = "[[obstacles]]\nvertices = [[1.5, 2.0], [2.5, 1.2], [3.5, 2.8], [2.2, 3.6]]\n"
    text = arena_toml("quad", extra=BALL.replace("1.0, 1.0", "4.0, 1.0") + quad
                      + "tolerance = 0.01\n")
    with pytest.raises(SpecError) as info:
        parse_spec(text)
    assert info.value.field == "obstacles[1]", str(info.value)
    reason = info.value.reason
    assert "tolerance 0.01" in reason and "too fine" in reason, reason
    assert "initial" not in reason and "target" not in reason, reason
    spec = parse_spec(text.replace("tolerance = 0.01", "tolerance = 0.05"))
    assert len([o for o in spec.obstacles if o.source == 1]) <= MAX_BOXES


def _random_polygon(rng, center, radius):
    angles = np.sort(rng.uniform(0.0, 2 * np.pi, int(rng.integers(3, 9))))
    return center + radius * np.c_[np.cos(angles), np.sin(angles)]


def test_polygon_box_hull_is_the_linear_programs_one():
    """The exact planar hull of ``polygon ∩ box`` contains the LP's (up to the LP's own
    tolerance) and is no larger than it (up to the rounding margin)."""
    rng = np.random.default_rng(3)
    for _ in range(200):
        shape = make_polytope(_random_polygon(rng, rng.uniform(1, 4, 2), rng.uniform(0.1, 1.0)),
                              "obstacles[0]")
        lo = rng.uniform(0.0, 4.0, 2)
        hi = lo + rng.uniform(0.0, 2.0, 2)
        exact, lp = shape.box_hull(lo, hi), shape._box_hull_lp(lo, hi)
        if lp is None or exact is None:
            # both empty, or the box only grazes the polygon within the LP's tolerance
            other = exact if lp is None else lp
            assert other is None or np.min(other[1] - other[0]) < 1e-6
            continue
        assert np.all(exact[0] <= lp[0] + 1e-7) and np.all(lp[1] <= exact[1] + 1e-7)
        assert np.all(lp[0] <= exact[0] + 1e-9) and np.all(exact[1] <= lp[1] + 1e-9)


def count_covering_work(monkeypatch) -> dict[str, list[int]]:
    """Count the work of each call of ``covering.cover`` (one entry per call): box hulls,
    corner-distance evaluations and the boxes of its bisection (before merging). A linear
    or quadratic program fails the test: a polygon's hulls and distances are closed forms."""
    import stt_codegen.spec.covering as covering
    from stt_codegen.spec.shapes import Polytope

    work: dict[str, list[int]] = {"hulls": [], "corners": [], "bisected": []}
    inside = [False]

    def count(key, function):
        def counted(*args, **kwargs):
            if inside[0]:
                work[key][-1] += 1
            return function(*args, **kwargs)
        return counted

    def cover_counted(*args, _cover=covering.cover, **kwargs):
        for values in work.values():
            values.append(0)
        inside[0] = True
        try:
            return _cover(*args, **kwargs)
        finally:
            inside[0] = False

    def bisect(*args, _bisect=covering._bisect, **kwargs):
        boxes = _bisect(*args, **kwargs)
        work["bisected"][-1] = len(boxes)
        return boxes

    def program(*args, **kwargs):
        raise AssertionError("a linear or quadratic program for a planar polygon")

    monkeypatch.setattr(covering, "cover", cover_counted)
    monkeypatch.setattr(covering, "_bisect", bisect)
    monkeypatch.setattr(Polytope, "box_hull", count("hulls", Polytope.box_hull))
    monkeypatch.setattr(covering, "_corner_distance", count("corners", covering._corner_distance))
    monkeypatch.setattr(Polytope, "_box_hull_lp", program)
    monkeypatch.setattr(Polytope, "_qp_distance", program)
    return work


def assert_bounded_work(work: dict[str, list[int]]) -> None:
    """Per covering, at most ``2 MAX_BOXES + 1`` boxes visited by the bisection (one hull
    and at most one corner evaluation each) and ``MERGE_WINDOW`` hulls per box and merge
    (at most twice the bisection's boxes): the bound of stt_codegen.spec.covering."""
    from stt_codegen.spec.covering import MERGE_WINDOW
    assert work["hulls"] and all(b > 0 for b in work["bisected"]), work
    for hulls, corners, boxes in zip(work["hulls"], work["corners"], work["bisected"]):
        bound = 2 * MAX_BOXES + 1 + 2 * MERGE_WINDOW * boxes
        assert 0 < hulls <= bound and 0 < corners <= bound, (hulls, corners, boxes)


@pytest.mark.slow
def test_eighty_polygons_are_covered_soundly_with_bounded_work(monkeypatch):
    """80 random convex polygons at tolerance 0.02 (the covering took
    about 30 s with a linear program per box hull). Every box is within the tolerance,
    random points of every polygon are covered, the result is the same twice, and the
    work is bounded: no linear or quadratic program, the covering's count of hulls and
    distances. ``stt-codegen bench covering`` gives the seconds (docs/performance.md)."""
    rng = np.random.default_rng(7)
    shapes = [make_polytope(_random_polygon(rng, rng.uniform(0.9, 4.1, 2),
                                            rng.uniform(0.05, 0.4)), "obstacles[0]")
              for _ in range(80)]
    forbidden = [START, (np.array([4.5, 4.5]), np.array([5.0, 5.0]))]
    work = count_covering_work(monkeypatch)
    coverings = [covering.cover(shape, 0.02, forbidden) for shape in shapes]
    assert len(work["hulls"]) == 80
    assert_bounded_work(work)
    for shape, boxes in zip(shapes, coverings):
        assert 0 < len(boxes) <= MAX_BOXES
        pts = np.array(shape.vertices)

        def in_polygon(r, pts=pts):
            return r.dirichlet(np.ones(len(pts)), 500) @ pts

        assert_valid_covering(shape, boxes, 0.02, forbidden, rng, in_polygon)
    again = cover(shapes[0], 0.02, forbidden)
    assert [(tuple(a), tuple(b)) for a, b in again] == [(tuple(a), tuple(b))
                                                        for a, b in coverings[0]]


def test_polygon_distance_is_the_quadratic_programs_one():
    """The planar closed form (all points and edges at once) agrees with the general QP."""
    rng = np.random.default_rng(5)
    for _ in range(20):
        shape = make_polytope(_random_polygon(rng, rng.uniform(1, 4, 2), rng.uniform(0.1, 1.0)),
                              "obstacles[0]")
        points = rng.uniform(0.0, 5.0, (30, 2))
        closed = shape.distance(points)
        qp = np.array([0.0 if np.all(shape.halfspaces[0] @ p <= shape.halfspaces[1] + 1e-12)
                       else shape._qp_distance(p) for p in points])
        assert closed.shape == (30,) and np.allclose(closed, qp, atol=1e-6)


@pytest.mark.slow
def test_eighty_polygons_design_with_bounded_work(monkeypatch):
    """The whole design of 80 polygons at tolerance 0.02 (774 boxes; it
    took 91 s, nearly all of it the covering) is certified; the covering of the spec's 80
    polygons does no linear or quadratic program and its bounded count of hulls and
    distances, and the certificate stays within its interval budget.
    ``stt-codegen bench covering`` gives the seconds of this very spec."""
    from stt_codegen_bench.arenas import make_arena
    from stt_codegen.design.certificate import MAX_INTERVALS
    work = count_covering_work(monkeypatch)
    spec = parse_spec(make_arena("polygons", 0, polygons=80, tolerance=0.02))
    assert len(work["hulls"]) == 80
    assert_bounded_work(work)
    found = design_tube(spec)
    assert len(spec.unsafe_sets) == 80 and len(spec.obstacles) > 80
    assert found.check.passed
    assert 0 < found.certificate.intervals <= MAX_INTERVALS
