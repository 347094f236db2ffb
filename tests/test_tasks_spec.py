"""``[[tasks]]`` in the spec (docs/tasks.md): the schema, the cross-field rules,
clear SpecErrors, the CLI's exit code, and specs without tasks unchanged."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from stt_codegen.cases import bundled_spec_bytes
from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import Spec, load_spec, parse_spec
from stt_codegen.spec.schema import json_schema


def doc(tasks: list, **extra) -> dict:
    return {"name": "timed", "prescribed_time": 10.0,
            "state_space": {"lower": [0.0, 0.0], "upper": [5.0, 5.0]},
            "initial": {"lower": [0.0, 0.0], "upper": [0.6, 0.6]},
            "target": {"lower": [4.4, 4.4], "upper": [5.0, 5.0]},
            "obstacles": [{"lower": [2.0, 2.0], "upper": [3.0, 3.0]}],
            "tasks": tasks, **extra}


REACH = {"kind": "reach", "window": [2.0, 3.0], "lower": [3.5, 0.5], "upper": [4.0, 1.0]}
STAY = {"kind": "stay", "window": [5.0, 6.0], "lower": [0.0, 3.5], "upper": [2.0, 5.0]}


def test_tasks_are_read_in_order_with_labels():
    any_of = {"kind": "reach", "window": [7.0, 8.0],
              "any_of": [{"lower": [3.5, 3.5], "upper": [4.0, 4.0]},
                         {"lower": [0.5, 3.5], "upper": [1.0, 4.0]}]}
    spec = Spec.from_dict(doc([REACH, STAY, any_of]))
    assert [(t.label, t.kind, t.window, len(t.boxes)) for t in spec.tasks] == [
        ("T1", "reach", (2.0, 3.0), 1), ("T2", "stay", (5.0, 6.0), 1),
        ("T3", "reach", (7.0, 8.0), 2)]
    assert spec.tasks[2].boxes[1].lower == (0.5, 3.5)


BAD = [
    ({**REACH, "kind": "always"}, "tasks[0].kind", "must be one of"),
    ({**REACH, "window": [2.0]}, "tasks[0].window", "[t0, t1]"),
    ({**REACH, "window": [3.0, 2.0]}, "tasks[0].window", "below"),
    ({**REACH, "window": [-1.0, 2.0]}, "tasks[0].window[0]", "non-negative"),
    ({**REACH, "window": [2.0, 11.0]}, "tasks[0].window", "after prescribed_time"),
    ({**REACH, "lower": [3.5, 0.5, 0.0]}, "tasks[0].lower", "2 entries"),
    ({**REACH, "upper": [3.5, 1.0]}, "tasks[0].lower", "not below"),
    ({**REACH, "upper": [6.0, 1.0]}, "tasks[0]", "not inside the state space"),
    ({**REACH, "lower": [2.5, 0.5], "upper": [4.0, 2.5]}, "tasks[0]", "meets obstacle 0"),
    ({"kind": "reach", "window": [2.0, 3.0]}, "tasks[0].lower", "missing"),
    ({**REACH, "any_of": [{"lower": [0.0, 3.5], "upper": [1.0, 4.0]}]}, "tasks[0].any_of",
     "not both"),
    ({"kind": "reach", "window": [2.0, 3.0], "any_of": []}, "tasks[0].any_of",
     "must not be empty"),
    ({"kind": "reach", "window": [2.0, 3.0], "any_of": [{"lower": [2.5, 2.5],
                                                          "upper": [3.5, 3.5]}]},
     "tasks[0].any_of", "every box meets an obstacle (any_of[0]: obstacle 0)"),
    ({**REACH, "colour": "red"}, "tasks[0].colour", "unknown key (allowed: any_of, duration, kind,"),
    ({"kind": "reach", "window": [2.0, 3.0], "any_of": [{"lower": [0.0, 3.5],
                                                          "upper": [1.0, 4.0], "x": 1}]},
     "tasks[0].any_of[0].x", "unknown key (allowed: lower, upper)"),
]


@pytest.mark.parametrize("task, field, reason", BAD)
def test_a_bad_task_is_a_spec_error_naming_the_field(task, field, reason):
    with pytest.raises(SpecError) as info:
        Spec.from_dict(doc([task]))
    assert info.value.field == field and reason in info.value.reason, str(info.value)


def test_windows_may_overlap_and_come_in_any_order():
    overlapping = {**REACH, "window": [5.5, 7.0]}
    spec = Spec.from_dict(doc([STAY, REACH, overlapping]))
    assert [t.window for t in spec.tasks] == [(5.0, 6.0), (2.0, 3.0), (5.5, 7.0)]
    assert spec.task_order == "listed"
    assert Spec.from_dict(doc([REACH], task_order={"order": "any"})).task_order == "any"
    with pytest.raises(SpecError) as info:
        Spec.from_dict(doc([REACH], task_order={"order": "shortest"}))
    assert info.value.field == "task_order.order"


def test_an_any_of_box_that_meets_an_obstacle_is_dropped_while_one_remains():
    """any_of for reach and stay; a box meeting the obstacle ([2, 3]^2) is dropped and
    noted, the others keep their any_of index."""
    boxes = [{"lower": [0.0, 3.5], "upper": [1.0, 4.0]},
             {"lower": [2.5, 2.5], "upper": [3.5, 3.5]},
             {"lower": [3.5, 0.5], "upper": [4.0, 1.0]}]
    spec = Spec.from_dict(doc([{"kind": "stay", "window": [5.0, 6.0], "any_of": boxes},
                               {"kind": "reach", "window": [7.0, 8.0], "any_of": boxes}]))
    for task in spec.tasks:
        assert task.any_of_index == (0, 2) and task.dropped == ((1, 0),)
        assert [b.lower for b in task.boxes] == [(0.0, 3.5), (3.5, 0.5)]
    with pytest.raises(SpecError) as info:     # a single box meeting one is still an error
        Spec.from_dict(doc([{**STAY, **boxes[1]}]))
    assert info.value.field == "tasks[0]" and "meets obstacle 0" in info.value.reason


def test_a_stay_duration_lies_in_its_window():
    spec = Spec.from_dict(doc([{**STAY, "window": [4.0, 8.0], "duration": 1.5},
                               {**STAY, "window": [8.0, 9.0], "duration": 1.0}]))
    assert [t.duration for t in spec.tasks] == [1.5, None]      # the whole window: None
    assert [t.held for t in spec.tasks] == [1.5, 1.0]
    for task, reason in (({**STAY, "duration": 2.0}, "longer than the window"),
                         ({**REACH, "duration": 0.5}, "only a stay task"),
                         ({**STAY, "duration": 0.0}, "positive")):
        with pytest.raises(SpecError) as info:
            Spec.from_dict(doc([task]))
        assert info.value.field == "tasks[0].duration" and reason in info.value.reason, \
            str(info.value)


def test_tasks_need_via_points_and_take_an_actuator_bound():
    with pytest.raises(SpecError) as info:
        Spec.from_dict(doc([REACH], tube={"method": "paper"}))
    assert info.value.field == "tube.method"
    spec = Spec.from_dict(doc([REACH], actuator={"input_bound": [1.0, 1.0]}))
    assert spec.tasks and spec.input_bound == (1.0, 1.0)


@pytest.mark.slow
def test_tasks_with_an_actuator_bound_are_designed_within_it_and_met():
    """tasks-visit with [actuator]: the bound is proved along the via tube, the certificate
    proves the tasks as without it, and the generated C meets both within the bound."""
    import dataclasses
    import stt_codegen as stt
    spec = stt.load_spec("tasks-visit")
    bound = (3.0, 3.0, 1.0)
    design = stt.design_tube(dataclasses.replace(spec, input_bound=bound))
    assert design.input_proof.meets(bound) and design.tube.input_bound == bound
    names = {m.name for m in design.certificate.margins if m.passed}
    assert {"task T1 reach", "task T2 reach"} <= names
    result = stt.simulate(design, backend="casadi")
    assert result.satisfied and all(task.met for task in result.tasks)
    assert all(u <= b for u, b in zip(result.max_abs_u, bound))


def test_cli_exits_2_without_traceback(tmp_path):
    text = bundled_spec_bytes("tasks-stay").decode().replace("window = [5.0, 7.0]",
                                                             "window = [5.0, 70.0]")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "design", str(path)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "tasks[0].window" in out.stderr


def test_a_spec_without_tasks_is_unchanged():
    """No tasks key, or an empty list: no tasks, and the same spec (hash of the file's
    bytes unchanged; the dict's hash is of the document as given)."""
    spec = load_spec("omnirobot-s1")
    assert spec.tasks == ()
    again = parse_spec(bundled_spec_bytes("omnirobot-s1"))
    assert again == spec and again.source_hash == spec.source_hash
    assert Spec.from_dict(doc([])).tasks == ()


def test_json_schema_describes_tasks():
    schema = json_schema()
    tasks = schema["properties"]["tasks"]
    assert tasks["type"] == "array"
    table = schema["$defs"]["TaskTable"]
    assert set(table["properties"]) == {"kind", "window", "lower", "upper", "any_of",
                                         "duration"}
    assert table["properties"]["kind"]["enum"] == ["reach", "stay"]
    assert schema["$defs"]["TaskOrderTable"]["properties"]["order"]["enum"] == ["listed", "any"]
    json.dumps(schema)
