"""Build small bare-metal programs for the Cortex-M4F and run them under QEMU mps2-an386."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from stt_codegen.embedded import board, build_elf, run_qemu
from stt_codegen.embedded.target import (BuildError, count_region_instructions,
                                         profile_regions)


MATH_PROGRAM = r"""
#include <math.h>
#include <stdio.h>

static int passed, failed;

static void check(const char *name, float got, float want)
{
    float tol = 4.0f * 1.1920929e-7f * (fabsf(want) > 1.0f ? fabsf(want) : 1.0f);
    int ok = isfinite(got) && fabsf(got - want) <= tol;
    printf("%s %.9e %s\n", name, (double)got, ok ? "ok" : "FAIL");
    if (ok) { ++passed; } else { ++failed; }
}

volatile float in_x = 0.75f;
volatile float in_y = 2.5f;

int main(void)
{
    float x = in_x, y = in_y;
    check("expf", expf(x), EXPF_WANT);
    check("logf", logf(y), LOGF_WANT);
    check("tanhf", tanhf(x - y), TANHF_WANT);
    check("fma", x * y + 1.0f, 2.875f);
    printf("%d passed, %d failed\n", passed, failed);
    return failed != 0;
}
"""


def _wants() -> dict[str, str]:
    f32 = np.float32
    return {
        "EXPF_WANT": repr(float(f32(math.exp(f32(0.75))))) + "f",
        "LOGF_WANT": repr(float(f32(math.log(f32(2.5))))) + "f",
        "TANHF_WANT": repr(float(f32(math.tanh(f32(0.75) - f32(2.5))))) + "f",
    }


def _build(tmp_path: Path, source: str, defines: dict | None = None, **kw):
    src = tmp_path / "main.c"
    src.write_text(source)
    return build_elf([src], out_dir=tmp_path / "build", defines=defines, **kw)


@pytest.mark.embedded
def test_float_maths_pass(tmp_path: Path) -> None:
    res = _build(tmp_path, MATH_PROGRAM, _wants())
    run = run_qemu(res.elf, timeout=60)
    assert not run.timed_out
    assert run.exit_code == 0, run.stdout
    assert "4 passed, 0 failed" in run.stdout
    values = dict(re.findall(r"^(\w+) (\S+) ok$", run.stdout, re.M))
    assert set(values) == {"expf", "logf", "tanhf", "fma"}
    assert float(values["expf"]) == pytest.approx(math.exp(0.75), rel=1e-6)
    assert float(values["tanhf"]) == pytest.approx(math.tanh(-1.75), rel=1e-6)
    # No absolute paths of this machine are written into the generated board files.
    for f in (tmp_path / "build" / "board").iterdir():
        assert str(tmp_path) not in f.read_text()
    assert res.elf_sizes["text"] > 0


@pytest.mark.embedded
def test_failing_program_exits_nonzero(tmp_path: Path) -> None:
    wants = _wants() | {"LOGF_WANT": "1.0f"}
    run = run_qemu(_build(tmp_path, MATH_PROGRAM, wants).elf, timeout=60)
    assert run.exit_code == 1
    assert "3 passed, 1 failed" in run.stdout
    assert "logf" in run.stdout and "FAIL" in run.stdout


@pytest.mark.embedded
def test_exit_status_passed_through(tmp_path: Path) -> None:
    src = "#include <stdlib.h>\nint main(void) { exit(42); }\n"
    assert run_qemu(_build(tmp_path, src).elf, timeout=30).exit_code == 42


@pytest.mark.embedded
def test_fault_gives_fault_status(tmp_path: Path) -> None:
    src = "int main(void) { __builtin_trap(); }\n"  # udf: UsageFault -> HardFault
    run = run_qemu(_build(tmp_path, src).elf, timeout=30)
    assert run.exit_code == board.FAULT_EXIT_STATUS
    assert "fault" in run.stderr


@pytest.mark.embedded
def test_timeout(tmp_path: Path) -> None:
    src = "int main(void) { for (;;) { __asm__ volatile(\"\"); } }\n"
    run = run_qemu(_build(tmp_path, src).elf, timeout=2)
    assert run.timed_out and run.exit_code is None


@pytest.mark.embedded
def test_build_error(tmp_path: Path) -> None:
    with pytest.raises(BuildError, match="error"):
        _build(tmp_path, "int main(void) { return undefined_thing; }\n")


COUNT_PROGRAM = r"""
#include <stdio.h>
#include <math.h>
#include "stt_target.h"

/* Exactly 6 instructions: 5 nops and bx lr. */
__attribute__((naked, noinline)) void six(void)
{
    __asm__ volatile("nop\n nop\n nop\n nop\n nop\n bx lr\n");
}

/* A loop of N iterations, 2 instructions each, + mov, bx lr: 2N + 2. */
__attribute__((naked, noinline)) void loop(unsigned n)
{
    (void)n;
    __asm__ volatile("1: subs r0, r0, #1\n bne 1b\n bx lr\n");
}

volatile float v = 0.3f;

int main(void)
{
    float r = 0.0f;
    stt_measure_begin(); stt_measure_end();
    stt_measure_begin(); six(); stt_measure_end();
    stt_measure_begin(); loop(10u); stt_measure_end();
    for (int i = 0; i < 3; ++i) {
        float a = v;
        stt_measure_begin(); r += expf(a); stt_measure_end();
    }
    printf("%f stack=%u\n", (double)r, (unsigned)stt_measured_stack_bytes());
    return 0;
}
"""


@pytest.mark.embedded
def test_instruction_counts(tmp_path: Path) -> None:
    run = run_qemu(_build(tmp_path, COUNT_PROGRAM).elf, timeout=60, count_instructions=True)
    assert run.exit_code == 0, run.stdout
    assert run.instructions is not None and len(run.instructions) == 6
    empty, six, loop, *exps = run.instructions
    assert empty == 0
    assert six == 1 + 6                 # bl six + body
    # loop(10u): movs r0, #10; bl; 10 x (subs, bne); bx lr
    assert loop == 1 + 1 + 2 * 10 + 1
    assert len(set(exps)) == 1 and 20 < exps[0] < 500  # same input, same path
    # the same regions split by function: they add up, six and loop run where they are
    assert run.functions is not None and len(run.functions) == 6
    assert [sum(v[0] for v in r.values()) for r in run.functions] == run.instructions
    assert run.functions[0] == {}
    assert run.functions[1]["six"] == [6, 1] and run.functions[1]["main"] == [1, 0]
    # loop branches back to its first instruction: 10 entries for 1 call
    assert run.functions[2]["loop"] == [2 * 10 + 1, 10]
    assert all(r["expf"][1] == 1 for r in run.functions[3:])
    stack = int(re.search(r"stack=(\d+)", run.stdout).group(1))
    assert 0 < stack < 512


@pytest.mark.embedded
def test_without_counting_no_counts(tmp_path: Path) -> None:
    run = run_qemu(_build(tmp_path, COUNT_PROGRAM).elf, timeout=60)
    assert run.exit_code == 0 and run.instructions is None


def test_count_parser() -> None:
    lines = [
        "Trace 0: 0x7f00 [00800408/000000c0/00000110/ff000201] stt_measure_begin",
        "Trace 0: 0x7f00 [00800408/000000c2/00000110/ff000201] stt_measure_begin",
        "Trace 0: 0x7f00 [00800408/00000100/00000110/ff000201] main",
        "Trace 0: 0x7f00 [00800408/00000200/00000110/ff000201] f",
        "Trace 0: 0x7f00 [00800408/00000104/00000110/ff000201] main",
        "Trace 0: 0x7f00 [00800408/000000d0/00000110/ff000201] stt_measure_end",
        "Trace 0: 0x7f00 [00800408/000000d2/00000110/ff000201] stt_measure_end",
    ]
    assert count_region_instructions(lines, (0xC0, 0xC4), 0xD0) == [2]
    # the two counted instructions: main's at 0x100 and f's first at 0x200
    functions = {"main": (0x100, 0x180), "f": (0x200, 0x210)}
    assert profile_regions(lines, (0xC0, 0xC4), 0xD0, functions) == [
        {"main": [1, 1], "f": [1, 1]}]
    assert profile_regions(lines, (0xC0, 0xC4), 0xD0, {"f": (0x200, 0x210)}) == [
        {"?": [1, 0], "f": [1, 1]}]
