"""The generated C refuses every compiler mode that assumes no NaN or infinity.

Such a mode folds ``isfinite`` to 1, so NaN and infinite inputs pass the input checks:
with clang ``-ffinite-math-only``, ``x[0] = NaN`` returned OK with ``u[0] = NaN``. The old
guard tested ``__FAST_MATH__`` only, which ``-ffinite-math-only`` and clang's
``-fno-honor-nans -fno-honor-infinities`` do not define (they define
``__FINITE_MATH_ONLY__ 1``). Each family must now stop the build with the guard's message.
"""

from __future__ import annotations

import subprocess

import pytest
from conftest import designed
from codegen_helpers import COMPILERS, files_of, write

GUARD = "must not be compiled with -ffast-math"
FAMILIES = [("gcc", ["-Ofast"]), ("gcc", ["-O2", "-ffast-math"]),
            ("gcc", ["-O2", "-ffinite-math-only"]),
            ("clang", ["-Ofast"]), ("clang", ["-O2", "-ffast-math"]),
            ("clang", ["-O2", "-ffinite-math-only"]),
            ("clang", ["-O2", "-fno-honor-nans", "-fno-honor-infinities"]),
            ("clang", ["-O2", "-ffp-model=fast"])]


def _defines(cc: str, mode: list[str]) -> str:
    return subprocess.run([cc, *mode, "-dM", "-E", "-x", "c", "/dev/null"],
                          capture_output=True, text=True, check=True).stdout


@pytest.mark.parametrize("cc, mode", FAMILIES, ids=[f"{c}{''.join(m)}" for c, m in FAMILIES])
def test_mode_sets_a_macro_the_guard_tests(cc, mode):
    if cc not in COMPILERS:
        pytest.skip(f"{cc} missing: install the Debian package {cc}")
    macros = _defines(cc, mode)
    assert "#define __FAST_MATH__ 1" in macros or "#define __FINITE_MATH_ONLY__ 1" in macros


@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("cc, mode", FAMILIES, ids=[f"{c}{''.join(m)}" for c, m in FAMILIES])
def test_mode_is_refused_with_the_guard_message(cc, mode, precision, tmp_path):
    if cc not in COMPILERS:
        pytest.skip(f"{cc} missing: install the Debian package {cc}")
    spec, _, _ = designed("omnirobot-s1")
    folder = write(tmp_path, files_of("omnirobot-s1", precision))
    proc = subprocess.run([cc, "-std=c99", *mode, "-c", f"{spec.c_name}.c"], cwd=folder,
                          capture_output=True, text=True)
    assert proc.returncode != 0 and GUARD in proc.stderr, proc.stderr[-1000:]


@pytest.mark.parametrize("cc", COMPILERS)
def test_ieee_modes_still_build(cc, tmp_path):
    """The guard does not refuse modes that keep NaN and infinities (``__FINITE_MATH_ONLY__ 0``)."""
    spec, _, _ = designed("omnirobot-s1")
    folder = write(tmp_path, files_of("omnirobot-s1", "double"))
    for mode in (["-O2"], ["-O2", "-fno-math-errno"], ["-O2", "-fno-trapping-math"]):
        assert "#define __FINITE_MATH_ONLY__ 1" not in _defines(cc, mode)
        proc = subprocess.run([cc, "-std=c99", *mode, "-c", f"{spec.c_name}.c"], cwd=folder,
                              capture_output=True, text=True)
        assert proc.returncode == 0, (mode, proc.stderr[-1000:])
