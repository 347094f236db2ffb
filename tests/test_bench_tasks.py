"""``stt-codegen bench tasks`` (issue 21): the seeded problems, the baseline's plan, the
report's arithmetic, the command's refusals."""

from __future__ import annotations

import numpy as np
import pytest

from stt_codegen.bench.task_arenas import task_problem, task_problem_toml
from stt_codegen.bench.task_baseline import plan_timed
from stt_codegen.bench.tasks_bench import METHODS, run_tasks_bench
from stt_codegen.cli import main
from stt_codegen.errors import SpecError


def test_problems_are_seeded_and_follow_the_protocol():
    assert task_problem_toml(0, 3) == task_problem_toml(0, 3)
    assert task_problem_toml(0, 3) != task_problem_toml(1, 3)
    counts = set()
    for k in range(12):
        spec = task_problem(0, k)
        m = len(spec.tasks)
        counts.add(m)
        assert m in (2, 3) and spec.prescribed_time == 4.0 * (m + 1)
        assert len(spec.tasks[0].boxes) == 2 and all(len(t.boxes) == 1 for t in spec.tasks[1:])
        assert [t.window for t in spec.tasks] == [(4.0 * j + 3.5, 4.0 * j + 4.5)
                                                  for j in range(m)]
    assert counts == {2, 3}


def test_baseline_plans_one_leg_per_task_and_one_to_the_target():
    spec = task_problem(0, 2)
    plan = plan_timed(spec)
    assert plan.reason == "" and len(plan.legs) == len(spec.tasks) + 1
    assert plan.switch == tuple(sum(t.window) / 2 for t in spec.tasks)
    # each leg ends where the next starts: at the chosen box's centre
    for leg, nxt, task, q in zip(plan.legs, plan.legs[1:], spec.tasks, plan.choices):
        assert np.allclose(leg[-1], task.boxes[q].center) and np.allclose(nxt[0], leg[-1])
    assert np.allclose(plan.legs[-1][-1], spec.target_set.center)


def test_count_and_seed_are_checked():
    with pytest.raises(SpecError) as info:
        run_tasks_bench(0, 0)
    assert info.value.field == "count"
    with pytest.raises(SpecError) as info:
        run_tasks_bench(1, -1)
    assert info.value.field == "seed"


def test_cli_refuses_a_bad_count_with_exit_2(capsys):
    assert main(["bench", "tasks", "--count", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "Traceback" not in err and "--count" in err


@pytest.mark.slow
def test_report_counts_what_the_problems_say():
    report = run_tasks_bench(2, 0)
    assert [p["index"] for p in report["problems"]] == [0, 1]
    for name in METHODS:
        rows = [p["methods"][name] for p in report["problems"]]
        assert report["summary"][name]["satisfied"] == sum(r["satisfied"] for r in rows)
        for r in rows:
            assert r["satisfied"] == (r["reason"] == "")
    assert report["stt_misses_baseline"] == [
        p["index"] for p in report["problems"]
        if p["methods"]["astar"]["satisfied"] and not p["methods"]["stt"]["satisfied"]]
