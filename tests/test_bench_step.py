"""bench step and bench scaling: structure and invariants of the reports (never speed)."""

from __future__ import annotations

import json
import shutil

import pytest

from stt_codegen_bench.harness import build_harness, harness_source
from stt_codegen_bench.scaling import format_scaling_report, run_scaling_bench, synthetic_design
from stt_codegen_bench.step import format_step_report, run_step_bench
from stt_codegen.cli import main
from stt_codegen.errors import SpecError
from stt_codegen.tube.model import build_model

IMPLEMENTATIONS = ["C, compiled loop", "C via ctypes (from Python)", "generated Python",
                   "CasADi Function (from Python)", "numpy reference"]
needs_valgrind = pytest.mark.skipif(shutil.which("valgrind") is None,
                                    reason="valgrind not installed (Debian package valgrind)")


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("STT_CODEGEN_CACHE", str(tmp_path / "cache"))


@pytest.mark.bench
@needs_valgrind
def test_step_report(capsys):
    assert main(["bench", "step", "omnirobot-s1", "--steps", "2000", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    rows = {r["name"]: r for r in report["implementations"]}
    assert list(rows) == IMPLEMENTATIONS
    assert rows["C, compiled loop"]["ratio_to_c"] == 1.0
    for r in rows.values():
        assert r["seconds_per_step"] > 0
        assert r["max_abs_u_difference"] < 1e-9  # the same step is timed everywhere
    assert report["inputs"] == 9000 and report["outside_tube_inputs"] == 0
    assert report["instructions_per_step"] > report["operations"]["arithmetic"]
    assert report["spec"] == "omnirobot-s1"
    text = format_step_report(report)
    assert "vs C loop" in text and "callgrind" in text


# CasADi's op codes by cost category, written here by hand: the count the benchmark reports
# (through the emitter's lowering and its op table) must agree with CasADi's own list.
_DATA_OPS = ("OP_INPUT", "OP_OUTPUT", "OP_CONST", "OP_PARAMETER", "OP_ASSIGN")
_LOGIC_OPS = ("OP_LT", "OP_LE", "OP_EQ", "OP_NE", "OP_NOT", "OP_AND", "OP_OR",
              "OP_IF_ELSE_ZERO")
_LIBRARY_OPS = ("OP_EXP", "OP_LOG", "OP_LOG1P", "OP_EXPM1", "OP_POW", "OP_CONSTPOW", "OP_SQRT",
                "OP_SIN", "OP_COS", "OP_TAN", "OP_ASIN", "OP_ACOS", "OP_ATAN", "OP_ATAN2",
                "OP_SINH", "OP_COSH", "OP_TANH", "OP_ASINH", "OP_ACOSH", "OP_ATANH", "OP_ERF",
                "OP_HYPOT")


@pytest.mark.bench
def test_step_operation_counts_match_casadis_instruction_list():
    """The benchmark's operation counts against CasADi's own instruction list of the step."""
    import casadi
    report = run_step_bench("omnirobot-s2", steps=500, rounds=1, callgrind=False)
    from stt_codegen.design.search import design_tube
    from stt_codegen.spec.loader import load_spec
    design = design_tube(load_spec("omnirobot-s2")).tube
    fn = build_model(design)["controller_step"]
    codes = [fn.instruction_id(k) for k in range(fn.n_instructions())]

    def count(names):
        wanted = {getattr(casadi, n) for n in names if hasattr(casadi, n)}
        return sum(code in wanted for code in codes)

    data, logic, library = count(_DATA_OPS), count(_LOGIC_OPS), count(_LIBRARY_OPS)
    assert report["operations"] == {"arithmetic": len(codes) - data - logic - library,
                                    "transcendental": library, "logic": logic,
                                    "total": len(codes)}
    assert library > 0 and logic > 0 and data > 0
    assert report["instructions_per_step"] is None


@pytest.mark.bench
@needs_valgrind
def test_callgrind_count_is_deterministic_and_per_step():
    harness = build_harness(synthetic_design(3, 2))
    try:
        a, b = harness.instructions_per_step(50), harness.instructions_per_step(50)
        assert a == b > 100
        t, x, alpha, outside = harness.record()
        assert t.shape == (9000,) and x.shape == (9000, 2) and alpha.shape == (9000, 4)
        assert x[0].tolist() == [0.25, 0.25] and (alpha[0] == 0).all()
    finally:
        harness.cleanup()
    assert not harness.folder.exists()


def test_harness_source_names_the_step():
    design = synthetic_design(1, 3)
    source = harness_source(design, "synthetic_m1_n3")
    assert "synthetic_m1_n3_step(" in source and "SYNTHETIC_M1_N3_N_ALPHA" in source
    assert "RECORD = 9000L" in source


def test_synthetic_designs():
    for mode in ("open", "closed", "random"):
        d = synthetic_design(12, 3, windows=mode)
        assert len(d.circumvents) == 12 and d.dimension == 3
        assert list(d.circumvents) == sorted(d.circumvents,
                                             key=lambda c: (c.dimension, c.side, c.obstacle))
        if mode == "open":
            assert all(c.start < 0 and c.end > d.prescribed_time for c in d.circumvents)
        if mode == "closed":
            assert all(c.start > d.prescribed_time for c in d.circumvents)
    assert synthetic_design(5, 2) == synthetic_design(5, 2)
    with pytest.raises(SpecError):
        synthetic_design(-1, 2)
    with pytest.raises(SpecError):
        synthetic_design(1, 0)


@pytest.mark.bench
@needs_valgrind
def test_scaling_report():
    report = run_scaling_bench([1, 6], [3], active_obstacles=4, sparse=(3, 60))
    sweep = report["obstacle_sweep"]
    assert [r["obstacles"] for r in sweep] == [1, 6]
    assert [r["dimension"] for r in report["dimension_sweep"]] == [3]
    for r in sweep + report["dimension_sweep"] + report["active_windows"]:
        assert "error" not in r and r["seconds_per_step"] > 0 and r["object_bytes"] > 0
    # more circumvents: a longer source (the table grows), the CasADi model has more
    # operations (it composes every circumvent)
    assert sweep[1]["source_bytes"] > sweep[0]["source_bytes"]
    assert sweep[1]["operations"]["transcendental"] > sweep[0]["operations"]["transcendental"]
    modes = {r["windows"]: r for r in report["active_windows"]}
    assert set(modes) == {"open", "random", "closed"}
    # the generated step evaluates only the open windows: closed ones cost less
    assert modes["closed"]["instructions_per_step"] < modes["open"]["instructions_per_step"]
    assert modes["open"]["outside_tube_inputs"] == modes["closed"]["outside_tube_inputs"] == 0
    assert "circumvents" in report["conclusion"]
    sparse = report["sparse_windows"]
    assert [r["obstacles"] for r in sparse["rows"]] == [3, 60]
    assert sparse["instruction_ratio"] is not None and sparse["instruction_ratio"] <= 3.0
    text = format_scaling_report(report)
    assert "obstacles (n = 2)" in text and "active windows" in text and "sparse windows" in text


@pytest.mark.slow
def test_generated_code_is_the_same_for_any_number_of_circumvents():
    """Only the tables (and their sizes) differ between 40 and 1000 circumvents (both with
    several circumvents on every bound: the code depends on n, the profiles and whether a
    bound has one or several circumvents, not on how many)."""
    import re

    from stt_codegen.codegen.generate import generate_files
    from stt_codegen.codegen.options import Options

    class _Spec:
        name, c_name, source_hash = "synthetic", "synthetic", "0" * 64
        delay = jitter = 0.0
        compensate_delay = False

    def code(m):
        files = generate_files(_Spec(), synthetic_design(m, 2, windows="sparse"),
                               Options(("c",), "double"))
        text = files["synthetic.c"].decode()
        text = re.sub(r"^  \{ .* \},? /\* obstacle \d+ \*/$\n", "", text, flags=re.MULTILINE)
        text = re.sub(r"^(static const \w+ \w+\[\w+\] = ).*$", r"\1", text, flags=re.MULTILINE)
        return re.sub(r"^#define SYNTHETIC_(N_WINDOWS|MAX_OPEN) \d+$", "", text, flags=re.MULTILINE)

    assert code(40) == code(1000)
