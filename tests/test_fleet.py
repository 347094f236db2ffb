"""Fleets (docs/fleets.md): the fleet spec, the prioritized design and the pair certificate."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import stt_codegen as stt
from stt_codegen.design.failures import FailureKind
from stt_codegen.design.fleet import CHUNK_SECONDS, certify_fleet, enclosed, tube_obstacles
from stt_codegen.design.samples import sample_tube

SI = {"controller": {"rate_hz": 100.0},
      "plant": {"model": "single-integrator", "disturbance_amplitude": 0.05}}

#: Two robots swapping corners of a 12 m x 8 m floor round a block: alone, their tubes
#: cross in the lower-left and upper-right aisles.
TWO = {
    "name": "two",
    "state_space": {"lower": [0.0, 0.0], "upper": [12.0, 8.0]},
    "obstacles": [{"lower": [3.0, 2.0], "upper": [9.0, 6.0]}],
    "robots": [
        {"name": "a", "radius": 0.2, "prescribed_time": 20.0, **SI,
         "initial": {"lower": [0.4, 0.6], "upper": [1.2, 1.4]},
         "target": {"lower": [10.8, 6.6], "upper": [11.6, 7.4]}},
        {"name": "b", "radius": 0.2, "prescribed_time": 20.0, **SI,
         "initial": {"lower": [10.8, 0.6], "upper": [11.6, 1.4]},
         "target": {"lower": [0.4, 6.6], "upper": [1.2, 7.4]}},
    ]}


def _two(**changes) -> dict:
    doc = copy.deepcopy(TWO)
    for path, value in changes.items():
        *keys, last = path.split("__")
        table = doc
        for key in keys:
            table = table[int(key)] if key.isdigit() else table[key]
        table[last] = value
    return doc


def _sampled_gap(designs, fleet) -> float:
    """The smallest, over the sampling instants of both tubes (each tube at its own
    instants, with ``alpha`` from the deployed implicit step), of the largest gap between
    the two robots' tube boxes along a body dimension minus both reaches; an independent
    evaluation of the tubes, not the certificate's enclosures."""
    a, b = fleet.robots
    sa, sb = (sample_tube(designs[r.name].tube, 1.5 * r.spec.prescribed_time)
              for r in fleet.robots)
    t = np.union1d(sa.t, sb.t)
    t = t[t <= min(sa.t[-1], sb.t[-1])]
    d = list(a.dims)

    def at(s, times):   # the box of the sampling interval holding each time
        k = np.searchsorted(s.t, times, side="right") - 1
        return s.gamma_lower[k][:, d], s.gamma_upper[k][:, d]
    la, ua = at(sa, t)
    lb, ub = at(sb, t)
    gap = np.maximum(lb - ua, la - ub).max(axis=1) - (a.reach + b.reach)
    return float(gap.min())


def test_a_fleet_file_is_one_single_spec_per_robot():
    fleet = stt.load_fleet("warehouse-fleet")
    assert len(fleet.robots) == 8
    variants = {r.spec.variant for r in fleet.robots}
    assert variants == {"first-order", "look-ahead"}
    for robot in fleet.robots:
        spec = robot.spec
        assert spec.name == robot.name
        assert spec.robot.radius == pytest.approx(robot.radius + spec.robot.offset)
        # the shared obstacles, inflated by this robot's reach
        assert len(spec.obstacles) == 3
        assert spec.obstacles[0].lower[0] == pytest.approx(3.5 - robot.reach)
    assert stt.bundled_fleets() == ["swap-fleet", "warehouse-fleet"]
    assert "warehouse-fleet" not in stt.bundled_cases()


@pytest.mark.parametrize("changes, field", [
    ({"robots__1__target__lower": [3.5, 3.0]}, "robots[1].target.lower"),
    ({"robots__0__radius": -1.0}, "robots[0].radius"),
    ({"robots__1__name": "a"}, "robots[1].name"),
    ({"robots__1__name": "1b"}, "robots[1].name"),
    ({"robots__0__speed": 1.0}, "robots[0].speed"),
    ({"robots__0__obstacles": []}, "robots[0].obstacles"),
    ({"robots__1__state_space": {"lower": [0.0, 0.0]}}, "robots[1].state_space.lower"),
    ({"robots__1__plant": {"model": "warp-drive"}}, "robots[1].plant.model"),
    ({"robots__0__initial": {"lower": [1.0, 2.5], "upper": [3.1, 3.0]}},
     "robots[0].initial"),
    ({"robots": []}, "robots"),
    ({"lanes": 2}, "lanes"),
])
def test_errors_name_the_robot_and_the_field(changes, field):
    with pytest.raises(stt.SpecError) as info:
        stt.FleetSpec.from_dict(_two(**changes))
    assert info.value.field.startswith(field), info.value


def test_a_missing_radius_is_named():
    doc = _two()
    del doc["robots"][1]["radius"]
    with pytest.raises(stt.SpecError, match=r"^robots\[1\]\.radius: missing"):
        stt.FleetSpec.from_dict(doc)


def test_tube_obstacles_cover_the_tube_grown_by_both_reaches():
    fleet = stt.FleetSpec.from_dict(TWO)
    design = stt.design_tube(fleet.robots[0].spec)
    tube = enclosed(design)
    enc = tube.enclosure         # a partition of [0, inf), as the pair certificate needs
    assert enc.t_start[0] == 0.0 and enc.t_end[-1] == np.inf
    assert np.array_equal(enc.t_end[:-1], enc.t_start[1:])
    assert np.all(enc.t_end[:-1] - enc.t_start[:-1] <= CHUNK_SECONDS + 1e-9)
    boxes = tube_obstacles(tube, 0.4, (0, 1), 10)
    assert [b.source for b in boxes] == list(range(10, 10 + len(boxes)))
    assert boxes[-1].active[1] == np.inf and boxes[0].active[0] == 0.0
    assert all(b.active[1] - b.active[0] <= CHUNK_SECONDS + 1e-9 for b in boxes[:-1])
    samples = sample_tube(design.tube, 30.0)
    for t, lo, hi in zip(samples.t, samples.gamma_lower, samples.gamma_upper):
        holding = [b for b in boxes if b.active[0] <= t <= b.active[1]]
        assert holding
        assert any(np.all(np.array(b.centres[0]) - b.half_size <= lo - 0.4 + 1e-9)
                   and np.all(np.array(b.centres[0]) + b.half_size >= hi + 0.4 - 1e-9)
                   for b in holding), t


def test_the_fleet_certificate_refuses_tubes_that_meet_for_a_short_interval():
    """Designed apart, each robot's tube is certified, but the two cross: the pair
    certificate fails, naming the pair and an interval, and the tubes evaluated at their
    sampling instants do overlap inside that interval."""
    fleet = stt.FleetSpec.from_dict(TWO)
    alone = {r.name: stt.design_tube(r.spec) for r in fleet.robots}
    assert all(d.certificate.passed for d in alone.values())
    (pair,) = certify_fleet(fleet, alone)
    assert not pair.passed and pair.pair == ("a", "b")
    assert pair.t_end - pair.t_start < 2.0               # a short interval
    assert pair.t_start <= pair.t_narrowest < pair.t_end
    assert f"a and b: their tubes, grown by both radii, may meet on [{pair.t_start:.4f}, " \
           f"{pair.t_end:.4f}] s" in pair.detail
    assert _sampled_gap(alone, fleet) < 0                # they really overlap


def test_a_shifted_second_robot_is_certified_apart():
    """The control: the same two robots, the second one's trip kept in the top aisle."""
    fleet = stt.FleetSpec.from_dict(_two(
        robots__1__initial={"lower": [10.8, 6.6], "upper": [11.6, 7.4]},
        robots__1__target={"lower": [0.4, 6.6], "upper": [1.2, 7.4]},
        robots__0__target={"lower": [10.8, 0.6], "upper": [11.6, 1.4]}))
    alone = {r.name: stt.design_tube(r.spec) for r in fleet.robots}
    (pair,) = certify_fleet(fleet, alone)
    assert pair.passed and pair.margin > 0
    assert _sampled_gap(alone, fleet) >= pair.margin - 1e-9


def test_the_prioritized_design_separates_the_crossing_robots(monkeypatch):
    from stt_codegen.design import fleet as fleet_design
    from stt_codegen.design.failures import advice_wanted
    retimings = []

    def retimed(*args):                      # each re-timing asks for a verdict only
        retimings.append(advice_wanted())
        return fleet_design_retimed(*args)

    fleet_design_retimed = fleet_design.retimed_design
    monkeypatch.setattr(fleet_design, "retimed_design", retimed)
    fleet = stt.FleetSpec.from_dict(TWO)
    designed = stt.design_fleet(fleet)
    assert retimings and not any(retimings)
    assert designed.certified and designed.order == ("a", "b")
    (pair,) = designed.pairs
    assert pair.passed and pair.margin > 0
    # the first robot keeps its way; the second one's tube is re-timed or re-planned in
    # space-time around the first one's, for its own task (spec) unchanged
    assert designed.designs["b"].motion and not designed.designs["a"].motion
    for robot in fleet.robots:
        assert designed.designs[robot.name].spec == robot.spec
    assert _sampled_gap(designed.designs, fleet) >= pair.margin - 1e-9
    assert "narrowest pair" in designed.summary()
    # the placements in order: a alone on the floor, then b with a near its way
    assert [(p.robot, p.placed, p.near) for p in designed.placements] == [("a", 0, 0),
                                                                          ("b", 1, 1)]


def test_a_target_on_another_robots_way_is_refused_naming_the_pair():
    """Robot b's target is robot a's target: whatever the order, the second one's target
    lies in the first one's tube after its t_c."""
    fleet = stt.FleetSpec.from_dict(_two(
        robots__1__target={"lower": [10.8, 6.6], "upper": [11.6, 7.4]}))
    with pytest.raises(stt.DesignError) as info:
        stt.design_fleet(fleet)
    assert info.value.kind is FailureKind.FLEET
    message = str(info.value)
    assert "a and b" in message or "b and a" in message


def test_the_fleet_schema_takes_the_bundled_fleet_and_refuses_an_unknown_robot_key():
    import tomllib

    import jsonschema

    from stt_codegen.cases import bundled_fleet_bytes
    from stt_codegen.spec.fleet import fleet_json_schema
    schema = fleet_json_schema()
    jsonschema.Draft7Validator.check_schema(schema)
    doc = tomllib.loads(bundled_fleet_bytes("warehouse-fleet").decode())
    jsonschema.validate(doc, schema)
    jsonschema.validate(TWO, schema)
    for bad in (_two(robots__0__speed=1.0), _two(lanes=2), _two(robots__1__radius=-1.0)):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(bad, schema)


def test_a_wait_between_two_re_timed_segments_is_a_held_segment():
    """The re-timing may wait at a via box between two segments; the tube's segments are
    contiguous, so the wait is a segment holding that box (a fleet's random floor met it)."""
    from stt_codegen.design.moving import _held
    from stt_codegen.tube.parameters import ReachSegment
    a = ReachSegment(0.0, 2.0, (0.0, 0.0), (1.0, 1.0), (2.0, 0.0), (3.0, 1.0), "smoothstep")
    b = ReachSegment(5.0, 7.0, (2.0, 0.0), (3.0, 1.0), (4.0, 2.0), (5.0, 3.0), "smoothstep")
    held = _held((a, b))
    assert len(held) == 3 and held[0] == a and held[2] == b
    wait = held[1]
    assert (wait.start, wait.end) == (2.0, 5.0)
    assert wait.lower_from == wait.lower_to == a.lower_to
    assert wait.upper_from == wait.upper_to == a.upper_to
    assert _held((a,)) == (a,)


def test_the_space_time_baseline_plans_every_robot_along_a_path_and_is_certified():
    from stt_codegen.design.fleet import PLANNER_SPACE_TIME
    fleet = stt.load_fleet("swap-fleet")
    designed = stt.design_fleet(fleet, planner=PLANNER_SPACE_TIME)
    assert designed.certified
    assert {d.motion for d in designed.designs.values()} == {"space-time path"}
    assert _sampled_gap(designed.designs, fleet) >= designed.narrowest.margin - 1e-9
    with pytest.raises(ValueError, match="planner"):
        stt.design_fleet(fleet, planner="astar")


def test_a_space_time_path_over_the_input_bound_is_planned_again_at_a_lower_speed(monkeypatch):
    """With ``[actuator]``, a space-time path whose input proof fails is planned again at
    each of ``PATH_SLOWER`` times its speed: the same path, later; the first proved one is
    kept, and when none is, the refusal says which speeds were tried."""
    from stt_codegen.design import fleet as fleet_design, moving
    doc = copy.deepcopy(TWO)
    for entry in doc["robots"]:
        entry["actuator"] = {"input_bound": [5.0, 5.0]}
    fleet = stt.FleetSpec.from_dict(doc)
    proved = fleet_design._proved
    monkeypatch.setattr(moving, "LEVEL_WINDOWS", ())      # the path's own timing: not levelled
    arrivals: list[float] = []

    def refused_at_first_speed(design, spec):    # the first try of each robot "fails"
        arrivals.append(max(s.end for s in design.tube.segments))
        return None if len(arrivals) % 2 else proved(design, spec)

    monkeypatch.setattr(fleet_design, "_proved", refused_at_first_speed)
    designed = stt.design_fleet(fleet, planner=fleet_design.PLANNER_SPACE_TIME)
    assert designed.certified and len(arrivals) == 4
    assert arrivals[1] > arrivals[0] and arrivals[3] > arrivals[2]    # slower: later
    for name in ("a", "b"):
        assert designed.designs[name].input_proof.meets((5.0, 5.0))
    arrivals.clear()
    monkeypatch.setattr(fleet_design, "_proved", lambda design, spec: arrivals.append(
        max(s.end for s in design.tube.segments)))
    with pytest.raises(stt.DesignError) as refused:
        stt.design_fleet(fleet, planner=fleet_design.PLANNER_SPACE_TIME)
    # each slower speed in turn, until one has no path within prescribed_time
    assert 2 <= len(arrivals) <= len(fleet_design.PATH_SLOWER)
    assert arrivals == sorted(arrivals) and arrivals[0] < arrivals[-1]
    assert "space-time path: its input is not proved within actuator.input_bound" in str(
        refused.value)


def test_a_space_time_path_under_an_input_bound_spends_its_waits_driving_slower(monkeypatch):
    """With ``[actuator]``, a space-time path's moves (at the grid's speed, 1.5 m/s, with
    waits) are levelled against the placed tubes: each robot arrives at its
    ``prescribed_time`` driving slower, its proved input peak lower, still certified."""
    from stt_codegen.design import fleet as fleet_design, moving
    doc = copy.deepcopy(TWO)
    for entry in doc["robots"]:
        entry["actuator"] = {"input_bound": [5.0, 5.0]}
    fleet = stt.FleetSpec.from_dict(doc)

    def fastest(design) -> float:
        return max(float(np.linalg.norm(np.subtract(s.lower_to, s.lower_from))) / (s.end - s.start)
                   for s in design.tube.segments)

    levelled = stt.design_fleet(fleet, planner=fleet_design.PLANNER_SPACE_TIME)
    monkeypatch.setattr(moving, "LEVEL_WINDOWS", ())
    raw = stt.design_fleet(fleet, planner=fleet_design.PLANNER_SPACE_TIME)
    assert levelled.certified and raw.certified
    for name in ("a", "b"):
        slow, fast = levelled.designs[name], raw.designs[name]
        assert slow.tube.segments[-1].end == 20.0 > fast.tube.segments[-1].end
        assert fastest(slow) < 0.85 * fastest(fast)
        assert max(slow.input_proof.peak) < 0.85 * max(fast.input_proof.peak)


def test_a_levelled_space_time_path_that_fails_its_check_gives_way_to_the_path_as_found(
        monkeypatch):
    """Where a levelled space-time path (arriving at ``t_c`` = 20 s) fails the whole check,
    the path as the search timed it is checked, and kept when it passes and its proof
    holds."""
    from dataclasses import replace as replaced
    from stt_codegen.design import fleet as fleet_design
    doc = copy.deepcopy(TWO)
    for entry in doc["robots"]:
        entry["actuator"] = {"input_bound": [5.0, 5.0]}
    real = fleet_design.check_tube

    def check(tube, spec):
        found = real(tube, spec)
        return replaced(found, passed=False) if tube.segments[-1].end == 20.0 else found

    monkeypatch.setattr(fleet_design, "check_tube", check)
    designed = stt.design_fleet(stt.FleetSpec.from_dict(doc),
                                planner=fleet_design.PLANNER_SPACE_TIME)
    assert designed.certified
    for name in ("a", "b"):
        design = designed.designs[name]
        assert design.tube.segments[-1].end < 20.0 and design.input_proof.meets((5.0, 5.0))


def test_a_placed_tube_whose_input_proof_fails_is_proved_once(monkeypatch):
    """The fleet proves the tube it placed: where that proof fails, the bound's procedure
    tries its slower variants, each of which would be the same tube proved again; none is
    tried. Within a bound it meets, the tube is proved once and carries its proof."""
    from dataclasses import replace as replaced
    from stt_codegen.design import actuator, fleet as fleet_design
    doc = copy.deepcopy(TWO)
    doc["robots"][0]["actuator"] = {"input_bound": [0.2, 0.2]}
    robot = stt.FleetSpec.from_dict(doc).robots[0]
    design = stt.design_tube(robot.spec.without_actuator())
    real = actuator.law13_input_proof
    proved: list = []
    monkeypatch.setattr(actuator, "law13_input_proof", lambda d, spec, *args: proved.append(
        d.tube.segments) or real(d, spec, *args))
    assert fleet_design._proved(design, robot.spec) is None
    assert proved == [design.tube.segments]
    proved.clear()
    kept = fleet_design._proved(design, replaced(robot.spec, input_bound=(50.0, 50.0)))
    assert kept is not None and kept.input_proof.meets((50.0, 50.0))
    assert kept.tube.segments == design.tube.segments and proved == [design.tube.segments]


def test_a_way_over_the_input_bound_gives_way_to_the_design_at_the_actuators_speed(
        monkeypatch):
    """A robot whose way (planned without ``[actuator]``) is not proved within the bound
    is placed with its design with ``[actuator]`` (the bound's procedure), which carries a
    proof within the bound; without that design it is refused with none placed."""
    from stt_codegen.design import fleet as fleet_design
    doc = copy.deepcopy(TWO)
    doc["robots"] = doc["robots"][:1]
    doc["robots"][0]["actuator"] = {"input_bound": [5.0, 5.0]}
    fleet = stt.FleetSpec.from_dict(doc)
    monkeypatch.setattr(fleet_design, "_proved", lambda design, spec: None)
    designed = stt.design_fleet(fleet)
    design = designed.designs["a"]
    assert designed.certified and design.certificate.passed
    assert design.input_proof.meets((5.0, 5.0))
    assert design.spec == fleet.robots[0].spec            # not the spec it was planned on
    monkeypatch.setattr(fleet_design, "_alone", lambda robot, placing: ())
    with pytest.raises(stt.DesignError) as refused:
        stt.design_fleet(fleet)
    assert "placed before it (none)" in str(refused.value)
    assert "its way: its input is not proved within actuator.input_bound" in str(
        refused.value)


def test_the_designs_at_the_actuators_speed_first_keep_clear_of_the_docks_crossed_alone():
    """Robot b parks in the upper aisle, where robot a's design alone passes: a's first
    design with [actuator] keeps clear of b's target box (grown by both reaches), its
    second is its design alone, which crosses it; b's design alone crosses no dock and is
    its only one. Each is proved within the bound."""
    from stt_codegen.design import fleet as fleet_design
    doc = copy.deepcopy(TWO)
    doc["robots"][1]["target"] = {"lower": [5.6, 6.6], "upper": [6.4, 7.4]}
    for entry in doc["robots"]:
        entry["actuator"] = {"input_bound": [5.0, 5.0]}
    fleet = stt.FleetSpec.from_dict(doc)
    placing = fleet_design._Placing(fleet, {})
    a, b = fleet.robots

    def crossed(robot, design):
        way = fleet_design.chunks(fleet_design.enclosed(design), robot.dims, 1.0)
        return [fleet_design._crosses(way, np.array(d.lower), np.array(d.upper))
                for d in fleet_design._docks(robot, fleet)]

    first, alone = fleet_design._alone(a, placing)
    assert crossed(a, first) == [False, False] and crossed(a, alone) == [False, True]
    assert alone.spec == a.spec and len(first.spec.obstacles) == len(a.spec.obstacles) + 1
    (only,) = fleet_design._alone(b, placing)
    assert not any(crossed(b, only))
    for design in (first, alone, only):
        assert design.certificate.passed and design.input_proof.meets((5.0, 5.0))
    assert fleet_design._alone(a, placing)[0] is first                  # computed once


@pytest.mark.slow
def test_a_re_ordering_keeps_the_placements_that_still_hold(monkeypatch):
    # warehouse-fleet moves two robots to the front; the robots placed before them keep
    # their placements where they are certified apart from the moved ones, so fewer
    # placements are designed than when every order starts afresh; certified either way
    from stt_codegen.design import fleet as F
    fits = []
    real = F._fit
    monkeypatch.setattr(F, "_fit", lambda robot, placing: fits.append(robot.name)
                        or real(robot, placing))
    kept = stt.design_fleet("warehouse-fleet")
    kept_fits, fits[:] = list(fits), []
    monkeypatch.setattr(F, "_kept_from", lambda *args: None)
    fresh = stt.design_fleet("warehouse-fleet")
    assert kept.certified and fresh.certified and kept.reordered == fresh.reordered != ()
    assert len(kept_fits) < len(fits)
    assert all(p.passed for p in kept.pairs) and len(kept.pairs) == 28



#: TWO with a third robot along the lower aisle, for the re-ordering tests.
THREE = copy.deepcopy(TWO)
THREE["robots"].append(dict(copy.deepcopy(TWO["robots"][0]), name="c",
                            initial={"lower": [4.0, 0.4], "upper": [4.6, 1.0]},
                            target={"lower": [7.4, 0.4], "upper": [8.0, 1.0]}))


def _scripted_failures(monkeypatch, failing: list[int]) -> list[list[str]]:
    """``design.fleet._place`` made to fail, on its ``j``-th call, the robot at position
    ``failing[j]`` of the order it is given (then the real placement); the orders it was
    called with."""
    from stt_codegen.design import fleet as F
    real, orders = F._place, []

    def place(order, placing, earlier=None):
        orders.append([r.name for r in order])
        if len(orders) <= len(failing):
            return order[failing[len(orders) - 1]], "scripted"
        return real(order, placing, earlier)

    monkeypatch.setattr(F, "_place", place)
    return orders


def test_a_robot_moved_once_goes_before_the_robot_moved_after_it(monkeypatch):
    # [p, q, r]: r fails (moved to the front), then q behind it (moved before r), then r
    # behind q: r goes before q, an order not tried yet, and the design goes on from there
    orders = _scripted_failures(monkeypatch, [-1, -1, 1])
    designed = stt.design_fleet(stt.FleetSpec.from_dict(THREE))
    p, q, r = orders[0]
    assert orders[1:4] == [[r, p, q], [q, r, p], [r, q, p]]
    assert designed.reordered == (r, q, r) and designed.certified


def test_an_order_is_not_tried_twice_and_a_robot_moves_at_most_twice(monkeypatch):
    from stt_codegen.design import fleet as F
    # [p, q]: q fails, then p behind q: [p, q] again, tried first: refused naming p
    orders = _scripted_failures(monkeypatch, [-1, -1])
    with pytest.raises(stt.DesignError, match=r"robot \w+: no tube avoids") as info:
        stt.design_fleet(stt.FleetSpec.from_dict(TWO))
    assert len(orders) == 2 and str(info.value).startswith(f"robot {orders[0][0]}:")
    # with one move per robot, the third failure (r behind q) is refused though [r, q, p]
    # was not tried
    monkeypatch.setattr(F, "MOVES_PER_ROBOT", 1)
    orders = _scripted_failures(monkeypatch, [-1, -1, 1])
    with pytest.raises(stt.DesignError) as info:
        stt.design_fleet(stt.FleetSpec.from_dict(THREE))
    assert len(orders) == 3 and str(info.value).startswith(f"robot {orders[0][2]}:")
