"""``stt-codegen simulate SPEC --sensed FILE``: a spec with ``[sensing]`` run among obstacles
its design does not know, listed in a TOML file (stt_codegen/runtime/walking_file.py)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stt_codegen.cli import main
from stt_codegen.runtime.backends import default_backend
from stt_codegen.runtime.sensed import WalkingObstacle, bundled_people
from stt_codegen.runtime.walking_file import load_walking_obstacles, walking_obstacles

#: hall-crossing's own people (runtime.sensed.bundled_people), as a file.
HALL_PEOPLE = """
[[walking_obstacles]]            # a person walking up across the hall
start = [5.0, 0.5]
radius = 0.3
velocity = [0.0, 0.5]

[[walking_obstacles]]            # another walking down its far side from t = 2 s
start = [7.0, 5.5]
radius = 0.35
path = [[2.0, 7.0, 5.5], [10.0, 7.0, 0.5]]
"""


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def test_a_file_reads_as_the_obstacles_it_lists(tmp_path):
    people = load_walking_obstacles(write(tmp_path, "people.toml", HALL_PEOPLE))
    assert people == bundled_people("hall-crossing")
    pursuer = walking_obstacles({"walking_obstacles": [
        {"start": [8, 3], "radius": 0.3, "pursuit_speed": 0.8, "pursuit_acceleration": 1}]})
    assert pursuer == (WalkingObstacle((8.0, 3.0), 0.3, pursuit_speed=0.8,
                                       pursuit_acceleration=1.0),)
    assert walking_obstacles({}) == ()


@pytest.mark.slow
def test_the_file_runs_the_same_loop_as_the_same_obstacles_given_in_python(tmp_path, capsys):
    """The case's own people (no ``--sensed``) and the same people from a file: the same
    run, in a different line of provenance only."""
    runs = []
    for extra in ([], ["--sensed", str(write(tmp_path, "people.toml", HALL_PEOPLE))]):
        assert main(["simulate", "hall-crossing", "--backend", "casadi", "--json", *extra]) == 0
        runs.append(json.loads(capsys.readouterr().out))
    case, from_file = runs
    assert case["sensed_obstacles"] == {"count": 2, "source": "case"}
    assert from_file["sensed_obstacles"] == {"count": 2, "source": "file"}
    assert case["sensing"]["switches"] > 0 and case["sensing"]["uncertified"] == []
    assert from_file["reach_time"] == case["reach_time"]
    assert from_file["min_obstacle_clearance"] == case["min_obstacle_clearance"]
    assert _without_times(from_file["sensing"]) == _without_times(case["sensing"])


def test_without_backend_the_command_runs_the_default_backend_as_plain_simulate(capsys):
    """``simulate`` of a spec with ``[sensing]`` and no ``--backend`` takes the library's
    default, as every other spec (it was passed on as ``None``: an unknown backend)."""
    assert main(["simulate", "hall-crossing", "--json"]) == 0
    run = json.loads(capsys.readouterr().out)
    assert run["backend"] == default_backend()
    assert run["sensed_obstacles"] == {"count": 2, "source": "case"}
    assert run["satisfied"] and run["sensing"]["switches"] > 0


def test_generating_a_sensing_spec_without_the_tube_as_data_says_what_it_wrote(
        tmp_path, capsys):
    """``generate`` of a spec with ``[sensing]`` writes its designed tube unless told
    ``--tube-data``: it says so, and names the option; with it, or for a spec without
    ``[sensing]``, no note."""
    for spec, extra, noted in (("hall-crossing", [], True),
                               ("hall-crossing", ["--tube-data"], False),
                               ("omnirobot-s1", [], False)):
        out = tmp_path / f"{spec}{len(extra)}"
        assert main(["generate", spec, "-o", str(out), "--lang", "python", *extra]) == 0
        said = capsys.readouterr().out
        assert ("note: hall-crossing has [sensing]: this controller runs its designed tube "
                "only; --tube-data writes" in said) == noted, said


def _without_times(record: dict) -> dict:
    """A sensing record without its processor times (they differ from run to run)."""
    events = [{k: v for k, v in event.items() if k != "cpu_s"} for event in record["events"]]
    return {**{k: v for k, v in record.items()
               if not k.startswith("replan_cpu") and k != "over_budget"}, "events": events}


def test_a_spec_file_with_sensing_and_no_obstacles_runs_its_replanning_among_none(
        tmp_path, capsys):
    """A copy of the case is a file: it has no people of its own, and says so."""
    spec = tmp_path / "hall.toml"
    spec.write_text((Path(__file__).parents[1] / "stt_codegen" / "cases" /
                     "hall-crossing.toml").read_text(encoding="utf-8"), encoding="utf-8")
    assert main(["simulate", str(spec), "--backend", "casadi"]) == 0
    out = capsys.readouterr().out
    assert "sensed obstacles: 0 (none given: --sensed FILE lists them" in out
    assert "0 switches" in out and "certified throughout" in out


BAD = {
    "start off the dims": ("[[walking_obstacles]]\nstart = [5.0, 0.5, 1.0]\nradius = 0.3\n",
                           "walking_obstacles[0].start: must have 2 entries"),
    "a boolean radius": ("[[walking_obstacles]]\nstart = [5.0, 0.5]\nradius = true\n",
                         "walking_obstacles[0].radius: must be a finite number, got True"),
    "an unknown key": ("[[walking_obstacles]]\nstart = [5.0, 0.5]\nradius = 0.3\nspeed = 3\n",
                       "walking_obstacles[0].speed: unknown key"),
    "two motions": ("[[walking_obstacles]]\nstart = [5.0, 0.5]\nradius = 0.3\n"
                    "velocity = [1.0, 0.0]\npursuit_speed = 3\n",
                    "walking_obstacles[0].pursuit_speed: give one of velocity, path"),
    "times not increasing": ("[[walking_obstacles]]\nstart = [5.0, 0.5]\nradius = 0.3\n"
                             "path = [[0.0, 1.0, 2.0], [0.0, 1.0, 2.0]]\n",
                             "walking_obstacles[0].path: rows (t, centre...) of 3 numbers, "
                             "times increasing"),
    "a table, not an array": ("[walking_obstacles]\nstart = [5.0, 0.5]\n",
                              "walking_obstacles: must be an array of tables"),
    "another table": ("walking = 3\n", "walking: unknown key"),
    "a text start": ("[[walking_obstacles]]\nstart = \"ab\"\nradius = 0.3\n",
                     "walking_obstacles[0].start: must be a non-empty array of numbers"),
    "no start": ("[[walking_obstacles]]\nradius = 0.3\n",
                 "walking_obstacles[1].start: missing"),
    "not TOML": ("[[walking_obstacles]\n", "--sensed: 'FILE': malformed TOML"),
    "a negative radius": ("[[walking_obstacles]]\nstart = [5.0, 0.5]\nradius = -0.3\n",
                          "walking_obstacles[0].radius: must be positive, got -0.3"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_bad_file_is_bad_input_named_by_its_entry_before_any_design(
        case, tmp_path, capsys, monkeypatch):
    text, message = BAD[case]
    if case == "no start":              # the second entry: named by its index
        text = "[[walking_obstacles]]\nstart = [1.0, 1.0]\nradius = 0.3\n" + text
    path = write(tmp_path, "people.toml", text)

    def no_design(*args, **kwargs):
        raise AssertionError("designed before the file was checked")
    monkeypatch.setattr("stt_codegen.design.search.design_tube", no_design)
    assert main(["simulate", "hall-crossing", "--sensed", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith("error: " + message.replace("FILE", str(path))), captured.err
    assert captured.out == "" and "Traceback" not in captured.err


@pytest.mark.parametrize("spec, message", [
    ("omnirobot-s1", "--sensed: spec 'omnirobot-s1' has no [sensing] table"),
    ("warehouse-fleet", "--sensed: a fleet's robots sense no obstacles"),
    ("hall-crossing", "--sensed: no file named"),
])
def test_sensed_obstacles_where_none_are_sensed_or_no_file_is_bad_input(
        spec, message, tmp_path, capsys):
    path = tmp_path / "people.toml"
    if spec != "hall-crossing":
        write(tmp_path, "people.toml", HALL_PEOPLE)
    assert main(["simulate", spec, "--sensed", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith("error: " + message), captured.err
    assert captured.out == ""


def test_design_says_how_the_tube_is_replanned_at_run_time(capsys):
    assert main(["design", "hall-crossing"]) == 0
    out = capsys.readouterr().out
    # the hall's envelope: every 0.5 s, L 0.1 s, tau 0.5 s, H 1 s, V 0.8 m/s
    assert ("sensing: this tube is the first plan, replanned every 0.5 s; each plan switches "
            "in 0.6 s after its measurement (latency 0.1 s + budget 0.5 s), certified 1 s on "
            "(0.5 s at least); obstacles of radius <= 0.4 m at <= 0.8 m/s, seen within 4 m "
            "on x1, x2, close 1.28 m within a plan's 1.6 s") in out
    assert main(["design", "omnirobot-s1"]) == 0
    assert "sensing" not in capsys.readouterr().out
