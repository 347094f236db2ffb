"""A one-dimensional spec (n = 1): its C builds under the project's warning flags.

gcc 12 rejected ``P_tube`` of a 1-state spec (``-Werror=maybe-uninitialized`` on
``g_u_dot[0]``), so ``simulate`` (C backend) and ``embedded`` exited 3.
"""

from __future__ import annotations

import subprocess
from functools import lru_cache
from pathlib import Path

import pytest
from codegen_helpers import COMPILERS, STRICT, write

from stt_codegen.codegen.generate import generate_files
from stt_codegen.codegen.options import Options
from stt_codegen.design.search import design_tube
from stt_codegen.spec.loader import load_spec

SPEC = Path(__file__).parent / "specs" / "line-s1.toml"

pytestmark = pytest.mark.skipif(not COMPILERS, reason="no C compiler (Debian: gcc, clang)")


@lru_cache(maxsize=None)
def _line():
    spec = load_spec(str(SPEC))
    return spec, design_tube(spec).tube


def test_the_spec_is_one_dimensional():
    _, design = _line()
    assert design.dimension == 1


@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("cc", COMPILERS)
@pytest.mark.parametrize("level", ["-O1", "-O2", "-O3", "-Os"])
def test_builds_warning_free_and_passes_its_selftest(precision, cc, level, tmp_path):
    spec, design = _line()
    folder = write(tmp_path, generate_files(spec, design, Options(("c",), precision)))
    prefix = spec.c_name
    flags = [f for f in STRICT if not f.startswith("-O")] + [level]
    proc = subprocess.run([cc, *flags, f"{prefix}.c", f"{prefix}_selftest.c", "-o", "selftest",
                           "-lm"], cwd=folder, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    run = subprocess.run([str(folder / "selftest")], capture_output=True, text=True)
    assert run.returncode == 0 and run.stdout.strip().endswith(" 0 failed"), run.stdout[-500:]


def test_simulate_with_the_c_backend():
    from stt_codegen.runtime.simulate import simulate
    result = simulate(design_tube(load_spec(str(SPEC))), backend="c")
    assert result.satisfied and result.stayed_in_tube
