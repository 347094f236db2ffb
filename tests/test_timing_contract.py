"""The timing contract of the generated code: every variant's header and Python module
carry the period, the delay and the jitter the certificate covers (the spec's
``[controller]``), with the contract's words, and a generation with a delay compiles and
passes its self-test."""

from __future__ import annotations

import dataclasses
import re
import shutil
import subprocess
import types

import pytest

import stt_codegen as stt

CASES = [("omnirobot-s1", 0.0002, 0.00001),     # law (13)
         ("office-base", 0.0005, 0.0),          # the look-ahead law
         ("second-order-s1", 0.0, 0.0)]         # the cascade (no delay in its certificate)


def _macro(header: str, prefix: str, name: str) -> float:
    found = re.search(rf"^#define {prefix}_{name} ([0-9.eE+-]+)f?$", header, flags=re.M)
    assert found is not None, name
    return float(found.group(1))


@pytest.mark.parametrize("case, delay, jitter", CASES)
def test_the_header_and_module_state_the_timing_the_proof_covers(tmp_path, case, delay,
                                                                 jitter):
    spec = stt.load_spec(case)
    design = stt.design_tube(spec)
    if delay or jitter:
        design = dataclasses.replace(design, spec=dataclasses.replace(spec, delay=delay,
                                                                      jitter=jitter))
    stt.generate(design, tmp_path / "out", precision="double")
    prefix = spec.c_name.upper()
    header = (tmp_path / "out" / f"{spec.c_name}.h").read_text()
    assert _macro(header, prefix, "PERIOD") == 1.0 / spec.rate_hz
    assert _macro(header, prefix, "DELAY") == delay
    assert _macro(header, prefix, "JITTER") == jitter
    assert "Timing contract" in header and "before the first u is applied" in header
    module = types.ModuleType("generated")
    exec((tmp_path / "out" / f"{spec.c_name}.py").read_text(), module.__dict__)
    assert (module.PERIOD, module.DELAY, module.JITTER) == (1.0 / spec.rate_hz, delay, jitter)
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler (Debian package gcc): the self-test is not run")
    run = subprocess.run(["make", "-s", "-C", str(tmp_path / "out"), "selftest"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.strip().splitlines()[-1].endswith(" 0 failed")


def test_the_single_precision_header_prints_float_literals(tmp_path):
    spec = stt.load_spec("omnirobot-s1")
    stt.generate(stt.design_tube(spec), tmp_path / "out", languages=["c"], precision="single")
    header = (tmp_path / "out" / f"{spec.c_name}.h").read_text()
    assert re.search(r"^#define OMNIROBOT_S1_PERIOD 0\.001f$", header, flags=re.M)


def test_the_design_document_states_the_timing():
    spec = dataclasses.replace(stt.load_spec("omnirobot-s1"), delay=0.00005, jitter=0.000001)
    timing = stt.design_tube(spec).to_json()["timing"]
    assert timing == {"rate_hz": 1000.0, "period_s": 0.001, "delay_s": 0.00005,
                      "jitter_s": 0.000001}


# ------------------------------------------------------------- the step's period check

#: dt off the period the tests call the step with, in periods.
OFF = 1.5


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    return str(tmp_path_factory.mktemp("off-period"))


def _inside_vectors(case, precision: str, count: int = 12) -> list[dict]:
    """Up to ``count`` of the case's shipped vectors whose state is strictly inside the
    tube(s) (the step's status OK, INPUT_CLAMPED or OFF_PERIOD): those of status OK first
    (office-base's are nearly all clamped), then the others, then the rest of status OK."""
    import json
    data = json.loads(case.files(precision)[f"{case.prefix}_vectors.json"])
    rows = data["vectors"] if "vectors" in data else [
        {k: data[k][i] for k in ("x", "t", "alpha", "status")} for i in range(len(data["t"]))]
    inside = [r for r in rows
              if r["status"] in (case.statuses[s] for s in ("OK", "OFF_PERIOD",
                                                            "INPUT_CLAMPED")
                                 if s in case.statuses)]
    ok = [r for r in inside if r["status"] == case.statuses["OK"]]
    others = [r for r in inside if r["status"] != case.statuses["OK"]]
    return (ok[:count // 2] + others + ok[count // 2:])[:count]


@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("variant", ["first-order", "cascade", "look-ahead"])
def test_the_step_reports_a_dt_other_than_the_period(variant, precision, root):
    """Every variant's generated C (double, single) and Python step at points strictly
    inside the tube(s): with dt = PERIOD the law's status (OK, or INPUT_CLAMPED under an
    actuator bound), with dt = 1.5 PERIOD OFF_PERIOD, with the same u; in double u and
    alpha_next at both dt are the CasADi step's (the model the code is printed from) bit
    for bit, and the Python module returns the C's statuses and outputs."""
    import numpy as np
    from codegen_helpers import COMPILERS
    from hard_helpers import c_api, hard_case
    from test_model_equivalence import casadi_outputs

    if not COMPILERS:
        pytest.skip("no C compiler (Debian package gcc)")
    case = hard_case(variant)
    st = case.statuses
    assert st["OFF_PERIOD"] == 5 and "Timing contract" in case.header
    lib = c_api(case, precision, COMPILERS[0], root)
    period = 1.0 / case.tube.rate_hz
    module = case.python()
    assert module.STATUS_OFF_PERIOD == 5 and module.PERIOD == period
    rows = _inside_vectors(case, precision)
    assert len(rows) >= 8
    laws, outputs = [], {}
    for k, row in enumerate(rows):
        x, a = lib.arr(row["x"]), lib.arr(row["alpha"])
        for dt in (period, OFF * period):
            u, nxt = lib.nan("N_INPUT"), lib.nan("N_ALPHA")
            status = lib.call("step", x=x, t=lib.dtype(row["t"]), dt=lib.dtype(dt), alpha=a,
                              u=u, alpha_next=nxt)
            outputs[k, dt] = (status, u, nxt)
        (law, u, _), (off, u_off, _) = outputs[k, period], outputs[k, OFF * period]
        assert law in (st["OK"], st.get("INPUT_CLAMPED")), (k, law)
        assert off == st["OFF_PERIOD"], (k, off)
        assert np.array_equal(u, u_off), k
        laws.append(law)
    assert st["OK"] in laws
    if precision == "single":
        return
    step = case.casadi_step()
    for dt in (period, OFF * period):
        got = casadi_outputs(step, {"x": np.array([r["x"] for r in rows]),
                                    "t": np.array([r["t"] for r in rows]),
                                    "dt": np.full(len(rows), dt),
                                    "alpha": np.array([r["alpha"] for r in rows])})
        for k, row in enumerate(rows):
            status, u, nxt = outputs[k, dt]
            assert np.array_equal(u, got[0][k]) and np.array_equal(nxt, got[1][k]), (k, dt)
            u_py, nxt_py, status_py = module.step(list(row["x"]), row["t"], dt,
                                                  list(row["alpha"]))
            assert status_py == status, (k, dt)
            assert np.array_equal(u_py, u) and np.array_equal(nxt_py, nxt), (k, dt)


@pytest.mark.parametrize("variant", ["first-order", "cascade", "look-ahead"])
def test_every_backend_reports_the_same_status_on_and_off_the_period(variant):
    """simulate's backends of each variant (the numpy reference, CasADi, the generated C
    and Python) return the same status at dt = PERIOD and at dt = 1.5 PERIOD (OFF_PERIOD
    where the law's is OK or INPUT_CLAMPED), and outputs bit for bit equal except the
    numpy reference's (within 1e-9)."""
    import numpy as np
    from codegen_helpers import COMPILERS
    from hard_helpers import hard_case

    from stt_codegen.runtime.backends import backend_names, make_controller
    from stt_codegen.tube.parameters import Status, step_status

    case = hard_case(variant)
    # the package's four (other tests may register more in the session)
    names = [n for n in ("reference", "casadi", "c", "python") if n != "c" or COMPILERS]
    assert set(names) <= set(backend_names(variant=variant))
    controllers = {n: make_controller(n, case.tube, case.design.stage) for n in names}
    period = 1.0 / case.tube.rate_hz
    rows = _inside_vectors(case, "double", 6)
    seen = set()
    for row in rows:
        x, a = np.array(row["x"]), np.array(row["alpha"])
        law = None
        for dt in (period, OFF * period):
            out = {n: c.step(x, row["t"], dt, a) for n, c in controllers.items()}
            statuses = {n: int(o[2]) for n, o in out.items()}
            assert len(set(statuses.values())) == 1, (dt, statuses)
            status = statuses["casadi"]
            law = status if law is None else law
            assert status == step_status(law, dt, case.tube.rate_hz)
            seen.add(status)
            for n, (u, nxt, _) in out.items():
                if n == "reference":
                    np.testing.assert_allclose(u, out["casadi"][0], rtol=1e-9, atol=1e-12)
                    np.testing.assert_allclose(nxt, out["casadi"][1], rtol=1e-9, atol=1e-12)
                else:
                    assert np.array_equal(u, out["casadi"][0]), n
                    assert np.array_equal(nxt, out["casadi"][1]), n
    assert Status.OFF_PERIOD in seen and seen & {Status.OK, Status.INPUT_CLAMPED}


def test_the_committed_vectors_cover_the_period_check():
    """Every committed generation's vectors (and so its self-test) hold, per variant, a
    vector at dt = PERIOD whose step status is OK and one off the period whose status is
    OFF_PERIOD; the first order's also ``control_status``, the law's (no OFF_PERIOD)."""
    import json
    from pathlib import Path

    from stt_codegen.tube.parameters import Status, off_period

    root = Path(__file__).resolve().parents[1] / "generated"
    variants = set()
    for path in sorted(root.glob("*/*/*_vectors.json")):
        data = json.loads(path.read_text())
        spec = stt.load_spec(path.parts[-3])
        rows = data["vectors"] if "vectors" in data else [
            {"dt": dt, "status": s} for dt, s in zip(data["dt"], data["status"])]
        pairs = {(bool(off_period(r["dt"], spec.rate_hz)), r["status"]) for r in rows}
        assert (False, Status.OK) in pairs and (True, Status.OFF_PERIOD) in pairs, path
        assert not {(False, Status.OFF_PERIOD)} & pairs, path
        assert not {(True, Status.OK), (True, Status.INPUT_CLAMPED)} & pairs, path
        if "control_status" in data:
            assert Status.OFF_PERIOD not in data["control_status"]
            assert all(c == s or s == Status.OFF_PERIOD
                       for c, s in zip(data["control_status"], data["status"]))
        variants.add(spec.variant)
    assert variants == {"first-order", "cascade", "look-ahead"}
