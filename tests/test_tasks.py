"""Timed tasks (docs/tasks.md): the design through the tasks' boxes, each task a
certified property for every t (rejected when violated between two samples), the
simulation's verdict, the generated C, and 3-D as 2-D."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from codegen_helpers import COMPILERS, self_test, write
from conftest import TASK_CASES, design_of

from stt_codegen.codegen.generate import Options, generate_files
from stt_codegen.design.certificate import certify_tube
from stt_codegen.design.failures import FailureKind
from stt_codegen.design.samples import sample_tube
from stt_codegen.design.search import base_design, design_tube
from stt_codegen.errors import DesignError
from stt_codegen.runtime.simulate import simulate
from stt_codegen.spec.loader import Spec
from stt_codegen.tube import reference
from stt_codegen.tube.parameters import SMOOTHSTEP, ReachSegment


def arena(n: int = 2, tasks: list | None = None, obstacles: list | None = None,
          t_c: float = 15.0) -> dict:
    """A 5 x 5 single-integrator arena (the other dimensions in [0, 2]) with tasks."""
    hi = [5.0, 5.0] + [2.0] * (n - 2)
    mid = [1.0] * (n - 2)
    return {"name": "timed", "prescribed_time": t_c,
            "state_space": {"lower": [0.0] * n, "upper": hi},
            "initial": {"lower": [0.0, 0.0] + [0.7] * (n - 2),
                        "upper": [0.6, 0.6] + [1.3] * (n - 2)},
            "target": {"lower": [4.4, 4.4] + [0.7] * (n - 2),
                       "upper": [5.0, 5.0] + [1.3] * (n - 2)},
            "obstacles": obstacles if obstacles is not None else
            [{"lower": [2.0, 2.0], "upper": [3.0, 3.0]}],
            "tasks": tasks or [], "tube": {"method": "via"},
            "_mid": mid}


def spec_of(doc: dict) -> Spec:
    return Spec.from_dict({k: v for k, v in doc.items() if not k.startswith("_")})


def box(lo: list, hi: list, n: int) -> dict:
    return {"lower": lo + [0.4] * (n - 2), "upper": hi + [1.6] * (n - 2)}


def visit_tasks(n: int) -> list:
    return [{"kind": "reach", "window": [4.0, 5.0],
             "any_of": [box([2.0, 3.4], [2.6, 4.0], n), box([3.4, 0.8], [4.0, 1.4], n)]},
            {"kind": "reach", "window": [9.0, 10.0], **box([4.2, 2.2], [4.8, 2.8], n)}]


def margins(certificate) -> dict:
    return {m.name: m for m in certificate.margins}


# --------------------------------------------------------------------------- design


def c_backend() -> str:
    if not COMPILERS:
        pytest.skip("no C compiler for the c backend (gcc or clang; Debian package gcc)")
    return "c"


@pytest.mark.parametrize("n", [2, 3])
def test_timed_goals_are_met_in_their_windows_and_certified(n):
    """2-D and 3-D alike: the tube goes through each task's box inside its window and
    the certificate proves it with a positive margin. T1's second box lies on the shorter
    path (centres' largest coordinate moves): the plans are tried shortest first."""
    from stt_codegen.design.tasks import _travel
    spec = spec_of(arena(n, visit_tasks(n)))
    base = base_design(spec)
    assert _travel(spec, base, (0, 1), (1, 0)) < _travel(spec, base, (0, 1), (0, 0))
    design = design_tube(spec)
    assert design.certificate.passed and design.task_choices == (1, 0)
    found = margins(design.certificate)
    for task in spec.tasks:
        m = found[task.name]
        assert m.passed and m.margin > 0.01
        assert task.window[0] <= m.time <= task.window[1]
    # the tube box is inside the task box at the middle of each reach window (the hold)
    samples = sample_tube(design.tube)
    for task, q in zip(spec.tasks, design.task_choices):
        k = int(round(np.mean(task.window) * design.tube.rate_hz))
        g_l, g_u, _, _ = reference.adaptive_tube(design.tube, samples.t[k:k + 1],
                                                 samples.alpha[k:k + 1])
        b = task.boxes[q]
        assert np.all(g_l[0] >= b.lower) and np.all(g_u[0] <= b.upper)
    doc = design.to_json()["tasks"]
    assert [(t["task"], t["alternative"], t["certified"]) for t in doc] == [
        ("T1", 1, True), ("T2", 0, True)]


@pytest.mark.slow
@pytest.mark.parametrize("n", [2, 3])
def test_timed_goals_are_met_in_closed_loop(n):
    """2-D and 3-D alike: the closed loop (generated C) meets each task in its window."""
    spec = spec_of(arena(n, visit_tasks(n)))
    result = simulate(design_tube(spec), backend=c_backend())
    assert result.satisfied and [t.met for t in result.tasks] == [True, True]
    for outcome, task in zip(result.tasks, spec.tasks):
        assert task.window[0] <= outcome.time <= task.window[1] and outcome.margin > 0


def test_any_of_takes_the_next_alternative_when_the_first_has_no_passage():
    """The alternative on the shorter path (T1's second) is walled off by obstacles: the
    design takes the other and says so."""
    n = 2
    tasks = visit_tasks(n)
    # wall the second box (x in [3.4, 4.0], y in [0.8, 1.4]) in with four obstacles
    walls = [{"lower": [3.0, 0.4], "upper": [4.4, 0.6]}, {"lower": [3.0, 1.6], "upper": [4.4, 1.8]},
             {"lower": [3.0, 0.6], "upper": [3.2, 1.6]}, {"lower": [4.2, 0.6], "upper": [4.4, 1.6]}]
    spec = spec_of(arena(n, tasks, obstacles=walls))
    design = design_tube(spec)
    assert design.task_choices == (0, 0)
    assert design.to_json()["tasks"][0]["alternative"] == 0
    assert margins(design.certificate)["task T1 reach"].passed


def test_stay_task_holds_the_tube_in_its_box_over_the_window():
    tasks = [{"kind": "stay", "window": [3.0, 6.0], "lower": [0.0, 3.5], "upper": [2.0, 5.0]}]
    spec = spec_of(arena(2, tasks, t_c=10.0))
    design = design_tube(spec)
    m = margins(design.certificate)["task T1 stay"]
    assert m.passed and m.margin > 0.01
    samples = sample_tube(design.tube)
    window = (samples.t >= 3.0) & (samples.t <= 6.0)
    g_l, g_u, _, _ = reference.adaptive_tube(design.tube, samples.t[window],
                                             samples.alpha[window])
    assert np.all(g_l >= [0.0, 3.5]) and np.all(g_u <= [2.0, 5.0])


def test_stay_window_from_zero_holds_the_start_box():
    """A stay window from t = 0 leaves no time to move: the tube holds X-hat_0 (inside the
    stay box) over it, and the certificate proves the stay from t = 0."""
    tasks = [{"kind": "stay", "window": [0.0, 2.0], "lower": [0.0, 0.0], "upper": [1.5, 1.5]},
             {"kind": "reach", "window": [5.0, 6.0], "lower": [3.0, 0.5], "upper": [3.6, 1.1]}]
    spec = spec_of(arena(2, tasks, obstacles=[], t_c=10.0))
    design = design_tube(spec)
    first = design.tube.segments[0]
    assert (first.start, first.end) == (0.0, 2.0) and first.lower_from == first.lower_to
    m = margins(design.certificate)["task T1 stay"]
    assert m.passed and m.time == 0.0
    # a start box that is not inside the stay box: no time to get there, refused
    tasks[0] = {**tasks[0], "lower": [0.3, 0.0]}
    with pytest.raises(DesignError) as info:
        design_tube(spec_of(arena(2, tasks, obstacles=[], t_c=10.0)))
    assert info.value.kind is FailureKind.TASK


def test_reach_window_from_zero_is_designed_and_certified():
    """A reach window may start at t = 0 (docs/tasks.md): its hold is the window's middle
    half, so the first leg has time; the certificate proves the task inside the window."""
    tasks = [{"kind": "reach", "window": [0.0, 0.5], "lower": [0.0, 0.0], "upper": [0.8, 0.8]}]
    design = design_tube(spec_of(arena(2, tasks, t_c=10.0)))
    hold = [s for s in design.tube.segments if s.lower_from == s.lower_to]
    assert (hold[0].start, hold[0].end) == (0.125, 0.375)
    m = margins(design.certificate)["task T1 reach"]
    assert m.passed and 0.0 <= m.time <= 0.5


@pytest.mark.slow
def test_stay_task_is_met_in_closed_loop():
    tasks = [{"kind": "stay", "window": [3.0, 6.0], "lower": [0.0, 3.5], "upper": [2.0, 5.0]}]
    result = simulate(design_tube(spec_of(arena(2, tasks, t_c=10.0))), backend=c_backend())
    assert result.satisfied and result.tasks[0].met and result.tasks[0].time is None
    assert result.tasks[0].margin > 0


@pytest.mark.slow
def test_simulation_judges_a_task_the_trajectory_misses():
    """The simulation's verdict is its own: a stay task the tube cannot keep (a tube
    designed for another spec) is judged not met, with when it failed, and the run is
    not satisfied."""
    tasks = [{"kind": "stay", "window": [3.0, 6.0], "lower": [0.0, 3.5], "upper": [2.0, 5.0]}]
    with_task = spec_of(arena(2, tasks, t_c=10.0))
    plain = design_tube(spec_of(arena(2, [], t_c=10.0)))
    from stt_codegen.runtime.simulate import run_closed_loop
    backend = c_backend()
    result = run_closed_loop(with_task, plain.tube, backend=backend)
    assert not result.tasks[0].met and not result.satisfied
    assert 3.0 <= result.tasks[0].time <= 6.0 and result.tasks[0].margin < 0
    assert "tasks" in result.to_json()
    without = simulate(plain, backend=backend)
    assert without.satisfied and "tasks" not in without.to_json()   # no tasks: as before


def test_no_time_between_tasks_is_a_design_error():
    tasks = [{"kind": "reach", "window": [0.0, 0.004], "lower": [4.0, 0.0], "upper": [5.0, 1.0]}]
    with pytest.raises(DesignError) as info:
        design_tube(spec_of(arena(2, tasks)))
    assert info.value.kind in (FailureKind.TASK, FailureKind.SAMPLING_RATE)


# --------------------------------------------------------------------------- certificate:
# a tube that satisfies a task at every sampling instant but violates it between two
# samples is rejected


def _tube_with(spec: Spec, pieces: list[tuple[float, tuple, tuple]]):
    """The spec's base tube with reach segments through ``(time, lower, upper)`` boxes
    (smoothstep between consecutive ones; the first at t = 0 is X-hat_0)."""
    base = base_design(spec)
    start = (0.0, base.initial_lower, base.initial_upper)
    points = [start] + pieces + [(spec.prescribed_time, base.target_lower, base.target_upper)]
    segments = tuple(ReachSegment(a[0], b[0], a[1], a[2], b[1], b[2], SMOOTHSTEP)
                     for a, b in zip(points, points[1:]))
    return replace(base, segments=segments, circumvents=())


def _centred(c, h=0.15):
    return tuple(v - h for v in c), tuple(v + h for v in c)


def _inside_at_samples(tube, task, t0, t1):
    samples = sample_tube(tube, horizon=t1 + 0.01)
    sel = (samples.t >= t0 - 1e-12) & (samples.t <= t1 + 1e-12)
    g_l, g_u, _, _ = reference.adaptive_tube(tube, samples.t[sel], samples.alpha[sel])
    b = task.boxes[0]
    return np.all(g_l >= b.lower, axis=1) & np.all(g_u <= b.upper, axis=1), samples.t[sel]


def test_reach_inside_only_at_two_samples_is_rejected():
    """The tube dips into the reach box at two consecutive sampling instants and is out
    of it between them and everywhere else: a check at samples would take the period
    between them as reached; the certificate does not."""
    tasks = [{"kind": "reach", "window": [4.0, 5.0], "lower": [2.0, 2.0], "upper": [3.0, 3.0]}]
    spec = spec_of(arena(2, tasks, obstacles=[]))
    dt = 1.0 / spec.rate_hz
    out, inside = _centred((3.3, 2.5)), _centred((2.6, 2.5))
    k = 4500
    pieces = [(2.0, *out), ((k - 0.5) * dt, *out), (k * dt, *inside), ((k + 0.5) * dt, *out),
              ((k + 1) * dt, *inside), ((k + 1.5) * dt, *out), (8.0, *out)]
    tube = _tube_with(spec, pieces)
    ok, t = _inside_at_samples(tube, spec.tasks[0], 4.0, 5.0)
    assert ok[np.isin(np.rint(t / dt), [k, k + 1])].all()    # in at both samples
    m = margins(certify_tube(tube, spec))["task T1 reach"]
    assert not m.passed, m
    # the same tube held inside over the two periods passes: the property can pass
    held = _tube_with(spec, [(2.0, *out), (4.2, *inside), (4.8, *inside), (6.0, *out),
                             (8.0, *out)])
    assert margins(certify_tube(held, spec))["task T1 reach"].passed


def test_stay_left_between_two_samples_is_rejected():
    """The tube is in the stay box at every sampling instant of the window but leaves it
    between two of them: rejected."""
    tasks = [{"kind": "stay", "window": [4.0, 6.0], "lower": [2.0, 2.0], "upper": [3.0, 3.0]}]
    spec = spec_of(arena(2, tasks, obstacles=[]))
    dt = 1.0 / spec.rate_hz
    inside, out = _centred((2.5, 2.5)), _centred((3.5, 2.5))
    k = 5000
    blip = [(k * dt, *inside), ((k + 0.5) * dt, *out), ((k + 1) * dt, *inside)]
    pieces = [(3.5, *inside)] + blip + [(6.5, *inside), (8.0, *inside)]
    tube = _tube_with(spec, pieces)
    ok, _ = _inside_at_samples(tube, spec.tasks[0], 4.0, 6.0)
    assert ok.all()                                           # in at every sample
    m = margins(certify_tube(tube, spec))["task T1 stay"]
    assert not m.passed, m
    steady = _tube_with(spec, [(3.5, *inside), (6.5, *inside), (8.0, *inside)])
    assert margins(certify_tube(steady, spec))["task T1 stay"].passed


# --------------------------------------------------------------------------- examples


@pytest.mark.parametrize("case", TASK_CASES)
def test_bundled_task_examples_design_and_certify(case):
    design = design_of(case)
    assert design.spec.tasks and design.certificate.passed
    names = [m.name for m in design.certificate.margins if m.name.startswith("task ")]
    assert names == [t.name for t in design.spec.tasks]
    text = json.dumps(design.to_json())
    assert '"tasks"' in text


@pytest.mark.slow
@pytest.mark.parametrize("case", TASK_CASES)
def test_bundled_task_examples_are_satisfied_with_the_c_backend(case):
    design = design_of(case)
    result = simulate(design, backend=c_backend())
    assert result.satisfied, result.to_json()
    assert all(t.met for t in result.tasks) and len(result.tasks) == len(design.spec.tasks)


@pytest.mark.slow
@pytest.mark.parametrize("precision", ["double", "single"])
def test_generated_c_of_a_task_example_passes_its_vectors(precision, tmp_path):
    if not COMPILERS:
        pytest.skip("no C compiler (gcc or clang; Debian package gcc)")
    design = design_of("tasks-visit")
    files = generate_files(design.spec, design.tube, Options(("c",), precision))
    folder = write(tmp_path, files)
    prefix = design.spec.c_name
    self_test(folder, prefix, COMPILERS[0], precision)
    # the task design's many segments are tables in the C, not new code
    assert len(design.tube.segments) > 3
