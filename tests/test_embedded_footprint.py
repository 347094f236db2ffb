"""Flash/RAM sizes and static worst-case stack of known object files."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from stt_codegen.embedded import build_elf, measure, run_qemu
from stt_codegen.embedded.footprint import FootprintError, worst_stack


# A "controller": a wrapper calling a body, like the generated code.
CTRL = r"""
#include <math.h>

int ctrl_calls = 5;                       /* .data: 4 bytes */
float ctrl_state[4];                      /* .bss: 16 bytes */
static const float ctrl_table[8] = {      /* .rodata: 32 bytes */
    0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f, 7.5f};

__attribute__((noinline)) float ctrl_body(float x, unsigned k)
{
    volatile float work[32];              /* >= 128 bytes of frame */
    for (unsigned i = 0; i < 32u; ++i) {
        work[i] = x * (float)i;
    }
    return work[k & 31u] + ctrl_table[k & 7u];
}

float ctrl_step(float x, unsigned k)
{
    ++ctrl_calls;
    ctrl_state[k & 3u] = ctrl_body(x, k);
    return expf(ctrl_state[k & 3u]);
}
"""

MAIN = r"""
#include <stdio.h>
#include "stt_target.h"
float ctrl_step(float x, unsigned k);
volatile float in = 0.01f;
int main(void)
{
    stt_measure_begin();
    float u = ctrl_step(in, 3u);
    stt_measure_end();
    printf("u=%f stack=%u\n", (double)u, (unsigned)stt_measured_stack_bytes());
    return 0;
}
"""


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory):
    d = tmp_path_factory.mktemp("footprint")
    (d / "ctrl.c").write_text(CTRL)
    (d / "main.c").write_text(MAIN)
    return build_elf([d / "ctrl.c", d / "main.c"], out_dir=d / "build")


@pytest.mark.embedded
def test_sizes_of_controller_object(built) -> None:
    fp = measure(built.objects[:1], built.su_files[:1], entry="ctrl_step")
    assert fp.data == 4
    assert fp.bss == 16
    assert fp.rodata == 32
    assert 40 < fp.text < 400
    assert fp.flash_bytes == fp.text + fp.rodata + fp.data
    assert fp.ram_bytes == fp.data + fp.bss
    # The driver's object is not counted.
    both = measure(built.objects, built.su_files)
    assert both.text > fp.text and both.stack_bytes is None


@pytest.mark.embedded
def test_static_stack_along_call_chain(built) -> None:
    fp = measure(built.objects[:1], built.su_files[:1], entry="ctrl_step")
    assert fp.stack_is_static
    assert fp.frames["ctrl_body"] >= 128
    assert fp.stack_chain == ("ctrl_step", "ctrl_body")
    assert fp.stack_bytes == fp.frames["ctrl_step"] + fp.frames["ctrl_body"]
    assert fp.unresolved == ("expf",)      # libm: not in the .su files, counted as 0
    assert fp.stack_dynamic == ()
    # .su files found next to the objects by default
    assert measure(built.objects[:1], entry="ctrl_step").stack_bytes == fp.stack_bytes


@pytest.mark.embedded
def test_painted_stack_consistent_with_static_bound(built) -> None:
    fp = measure(built.objects[:1], entry="ctrl_step")
    run = run_qemu(built.elf, timeout=60, count_instructions=True)
    assert run.exit_code == 0, run.stdout + run.stderr
    painted = int(re.search(r"stack=(\d+)", run.stdout).group(1))
    # Measured: at least the body's frame, at most the static bound plus expf's own stack.
    assert fp.frames["ctrl_body"] <= painted <= fp.stack_bytes + 256
    assert run.instructions is not None and len(run.instructions) == 1
    assert run.instructions[0] > 32 * 3  # the loop of 32 stores alone


def test_worst_stack_picks_deepest_path_and_rejects_recursion() -> None:
    frames = {"a": 8, "b": 100, "c": 16, "d": 64}
    graph = {"a": {"b", "c"}, "c": {"d"}, "b": set(), "d": set()}
    assert worst_stack("a", frames, graph)[:2] == (108, ("a", "b"))
    frames["d"] = 120
    assert worst_stack("a", frames, graph)[:2] == (144, ("a", "c", "d"))
    with pytest.raises(FootprintError, match="recursion"):
        worst_stack("a", frames, {"a": {"c"}, "c": {"a"}})
    with pytest.raises(FootprintError, match="not found"):
        worst_stack("zz", frames, graph)


@pytest.mark.embedded
def test_su_files_written(built) -> None:
    for su in built.su_files:
        assert Path(su).exists()
    text = Path(built.su_files[0]).read_text()
    assert re.search(r":ctrl_body\t\d+\tstatic", text)
