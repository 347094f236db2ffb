"""`stt-codegen embedded`: the single-precision controller on the emulated Cortex-M4F.

For every bundled case: all self-test vectors pass on QEMU mps2-an386, the errors stay
within the single-precision bound of stt_codegen.codegen.tolerance, and the closed loop
(9000 steps, plant compiled in) is satisfied and agrees with the host simulation.
"""

from __future__ import annotations

import json

import pytest

from conftest import CASES
from stt_codegen.cli import main


@pytest.fixture(scope="module")
def reports(tmp_path_factory) -> dict:
    return {}


def _report(case, reports, tmp_path_factory, capsys) -> dict:
    if case not in reports:
        build = tmp_path_factory.mktemp(f"emb-{case}")
        code = main(["embedded", case, "--json", "--build-dir", str(build / "b")])
        out = capsys.readouterr().out
        reports[case] = (code, json.loads(out))
    return reports[case]


@pytest.mark.embedded
@pytest.mark.parametrize("case", CASES)
def test_embedded_case(case, reports, tmp_path_factory, capsys) -> None:
    code, r = _report(case, reports, tmp_path_factory, capsys)
    assert code == 0 and r["ok"]
    # (a) the generated self-test on the target
    assert r["vectors_failed"] == 0 and r["vectors_passed"] > 500
    # the same vectors compared with the double reference: within the stated bound
    assert r["status_mismatches"] == 0
    assert all(v <= 1.0 for v in r["error_to_bound"].values()), r["error_to_bound"]
    assert 0 < r["max_rel_error_u"] < 1e-2
    # (b) the closed loop on the target, judged like the host simulation
    assert r["closed_loop_satisfied"] and r["reached"] and not r["collision"]
    assert not r["left_state_space"] and r["outside_tube_steps"] == 0
    assert r["steps"] == 9000 and r["reach_time"] <= 9.0 and r["min_clearance"] > 0.05
    assert r["host_satisfied"]
    assert r["max_state_deviation"] < 1e-3          # float controller vs double on the host
    assert abs(r["reach_time"] - r["host_reach_time"]) <= 0.005
    # footprint and cost
    assert 0 < r["flash_bytes_linked"] < r["flash_bytes"] < 64 * 1024
    assert r["ram_bytes"] == 0                          # no mutable state
    assert r["stack_chain"][0] == case.replace("-", "_") + "_step"
    assert r["stack_detail"]["su_bytes"] <= r["stack_bytes"] < 1024
    assert 0 < r["stack_bytes_measured"] <= r["stack_bytes"]
    counts = r["instructions_detail"]["counts"]
    assert len(counts) == len(r["instructions_detail"]["steps"]) >= 5
    assert all(1000 < c < 50000 for c in counts)
    assert max(counts) < 1.3 * min(counts)             # branch-free body, libm varies a little
    assert r["instructions_per_step"] == round(sum(counts) / len(counts))
    # the timing contract's budget: the worst measured step at 168 MHz, within the period
    assert r["instructions_worst"] == max(counts) and r["steps_measured"] == len(counts)
    assert r["period_share_lower"] == pytest.approx(max(counts) / 168e6 * 1000.0)
    assert r["period_share_lower"] < 0.2
    # where they go: the per-function means add up to the mean count; every exp of a
    # normal step takes stt_expf's fast path (newlib's expf is never entered)
    by_function = r["instructions_detail"]["by_function"]
    total = sum(v["instructions"] for v in by_function.values())
    assert abs(total - sum(counts) / len(counts)) <= 0.05 * len(by_function) + 1e-9
    assert by_function[case.replace("-", "_") + "_step"]["entries"] == 1
    # (gcc may split off the fast path as stt_expf.part.0, the guard inlined in the callers)
    own = [v["entries"] for name, v in by_function.items() if name.startswith("stt_expf")]
    assert max(own) >= 6                                 # the trigger's six
    assert "expf" not in by_function and "__ieee754_expf" not in by_function
    # and every log of law (13) stt_logf's (newlib's logf is never entered)
    assert any(name.startswith("stt_logf") for name in by_function)
    assert "logf" not in by_function and "__ieee754_logf" not in by_function


@pytest.mark.embedded
def test_embedded_text_output(capsys, tmp_path) -> None:
    code = main(["embedded", "omnirobot-s2", "--no-host", "--build-dir", str(tmp_path / "b")])
    out = capsys.readouterr().out
    assert code == 0
    assert "0 failed" in out and "closed loop: satisfied" in out
    assert "instructions per step" in out


def test_embedded_missing_tools_exit_3(monkeypatch, capsys) -> None:
    """A missing tool is a toolchain failure (exit 3), not bad input."""
    import stt_codegen.embedded.deploy as deploy
    monkeypatch.setattr(deploy, "missing_message", lambda: (
        "missing qemu-system-arm; install the Debian packages: apt-get install -y "
        "qemu-system-arm"))
    assert main(["embedded", "omnirobot-s1"]) == 3
    err = capsys.readouterr().err
    assert err.startswith("error: missing qemu-system-arm") and "apt-get install" in err


def test_embedded_bad_spec_exit_2(capsys, tmp_path) -> None:
    assert main(["embedded", str(tmp_path / "nope.toml")]) == 2
    assert capsys.readouterr().err.startswith("error: ")
