"""bench arenas end to end: local processes, a local Dask cluster, the CLI and its errors."""

from __future__ import annotations

import json
import operator

import pytest

from stt_codegen_bench import arenas_bench, parallel
from stt_codegen_bench.arena_job import METHODS
from stt_codegen_bench.parallel import run_parallel
from stt_codegen.cli import main
from stt_codegen.errors import SpecError

SUMMARY_KEYS = {"runs", "successes", "success_rate", "time_median_s", "time_p95_s", "failures",
                "effort_runs", "peak_u_median", "peak_u_p95", "effort_median", "effort_p95",
                "max_abs_e_median", "max_abs_e_max"}


def test_local_pool_keeps_the_order():
    calls = [(k, 10) for k in range(7)]
    assert run_parallel(operator.mul, calls, workers=2, progress=False) == [10 * k for k in range(7)]
    with pytest.raises(SpecError, match="workers"):
        run_parallel(operator.mul, calls, workers=0, progress=False)


@pytest.mark.bench
def test_arenas_json_on_local_processes(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    specs = tmp_path / "specs"
    specs.mkdir()
    code = main(["bench", "arenas", "--count", "2", "--seed", "5", "--workers", "2",
                 "--json", "--specs", str(specs)])
    captured = capsys.readouterr()
    assert code == 0
    report = json.loads(captured.out)
    methods, skipped = arenas_bench.available_methods()
    assert set(report["methods"]) == set(methods) and set(methods) | set(skipped) == set(METHODS)
    for summary in report["methods"].values():
        assert set(summary) == SUMMARY_KEYS and summary["runs"] == 2
        assert summary["successes"] + sum(summary["failures"].values()) == 2
        assert summary["time_median_s"] <= summary["time_p95_s"]
        assert summary["effort_runs"] == summary["successes"]
        if summary["effort_runs"]:
            assert 0 < summary["peak_u_median"] <= summary["peak_u_p95"]
            assert 0 < summary["effort_median"] <= summary["effort_p95"]
    assert [a["name"] for a in report["arenas"]] == ["arena-5-0", "arena-5-1"]
    assert sorted(p.name for p in specs.iterdir()) == ["arena-5-0.toml", "arena-5-1.toml"]
    assert report["machine"]["cpus"] >= 1
    assert "leaked" not in captured.err  # OMPL stays in the worker processes


@pytest.mark.bench
def test_arenas_table(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    assert main(["bench", "arenas", "--count", "1", "--methods", "astar", "--workers", "1",
                 "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "A* + tracker" in out and "time median" in out and "machine:" in out
    assert "peak |u| median" in out and "effort p95" in out


@pytest.mark.bench
def test_arenas_on_a_dask_cluster(tmp_path, monkeypatch):
    distributed = pytest.importorskip("distributed")
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        report = arenas_bench.run_arenas_bench(2, 0, scheduler=cluster.scheduler_address,
                                               methods=("stt", "astar"), progress=False)
    assert report["scheduler"] and set(report["methods"]) == {"stt", "astar"}
    assert [a["index"] for a in report["arenas"]] == [0, 1]
    local = arenas_bench.run_arenas_bench(2, 0, workers=1, methods=("stt", "astar"),
                                          progress=False)
    for a, b in zip(report["arenas"], local["arenas"]):  # same outcomes wherever it runs
        for m in ("stt", "astar"):
            assert a["methods"][m]["success"] == b["methods"][m]["success"]
            assert a["methods"][m]["reach_time"] == b["methods"][m]["reach_time"]


@pytest.mark.parametrize("argv,field", [
    (["bench", "arenas", "--count", "0"], "--count"),
    (["bench", "arenas", "--count", "1", "--workers", "0"], "--workers"),
    (["bench", "arenas", "--count", "1", "--methods", "dijkstra"], "--methods"),
    (["bench", "arenas", "--count", "1", "--specs", "/nonexistent/folder"], "--specs"),
    (["bench", "arenas", "--count", "1", "--scheduler", "tcp://127.0.0.1:9"], "--scheduler"),
    (["bench", "step", "no-such-case"], ""),
    (["bench", "step", "omnirobot-s1", "--steps", "0"], "--steps"),
    (["bench", "scaling", "--obstacles", "1,x"], "--obstacles"),
    (["bench", "scaling", "--dimensions", "0"], "--dimensions"),
    (["bench", "covering", "--count", "-1"], "--count"),
    (["bench", "covering", "--tolerance", "0"], "--tolerance"),
    (["bench", "alpha", "no-such-case"], ""),
])
def test_bad_input_exits_2_without_traceback(argv, field, capsys, monkeypatch):
    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", "1s")
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "Traceback" not in err
    assert field in err


def test_negative_seed_is_an_argparse_error(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["bench", "arenas", "--seed", "-1"])
    assert exc.value.code == 2
