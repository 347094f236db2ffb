"""Generated files do not depend on the CPU: numpy's SIMD kernels, and rounding to a few digits.

numpy picks ``exp``/``log``/``tanh`` kernels at run time from the CPU's features, and they
differ in the last bits. The generator rounds what such kernels feed into a generated file
(:mod:`stt_codegen.rounding`), and the oracle's printed values use libm. Here the committed
``generated/`` is regenerated with numpy limited to its baseline kernels
(``NPY_DISABLE_CPU_FEATURES`` naming every feature numpy dispatches to on this machine), as
on a CPU without them, and one level down; ``.ci/run`` checks every level, and the oldest
numpy allowed.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from stt_codegen.rounding import DIGITS, round_down, round_up, round_up_array

REPO = Path(__file__).resolve().parents[1]


def _dispatched() -> list[str]:
    out = subprocess.run([sys.executable, str(REPO / ".ci" / "numpy-dispatched")],
                         capture_output=True, text=True, check=True)
    return out.stdout.split()


@pytest.mark.slow
@pytest.mark.parametrize("level", ["baseline", "below the highest"])
def test_generated_is_the_same_with_numpy_limited_to_a_lower_cpu_level(level):
    """``baseline``: every dispatched feature off (and OpenBLAS's generic core); ``below the
    highest``: the highest one off, as on a CPU one level down. ``.ci/run`` checks every
    level (on an AVX-512 machine that includes AVX2's, where the drift was first seen)."""
    features = _dispatched()
    if not features:
        pytest.skip("numpy dispatches to no SIMD feature on this machine: its kernels are "
                    "already the baseline's")
    off = features if level == "baseline" else features[-1:]
    env = dict(os.environ, NPY_DISABLE_CPU_FEATURES=" ".join(off))
    if level == "baseline":
        env["OPENBLAS_CORETYPE"] = "Prescott"
    done = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "check"], env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, (off, done.stdout[-3000:], done.stderr[-2000:])
    assert "generated/ is up to date" in done.stdout


finite = st.floats(allow_nan=False, allow_infinity=False)


@given(finite, st.integers(1, 17))
def test_rounding_brackets_the_number_with_few_digits(x, digits):
    low, high = round_down(x, digits), round_up(x, digits)
    assert low <= x <= high
    for value in (low, high):
        if value != 0.0:
            # at most `digits` significant digits (the float nearest a short decimal)
            assert float(f"{value:.{digits - 1}e}") == value, value


@given(st.floats(min_value=1e-300, max_value=1e300))
def test_rounding_is_tight(x):
    """The bracket is one unit of the last kept digit wide at most."""
    unit = 10.0 ** (math.floor(math.log10(x)) - DIGITS + 1)
    assert round_up(x) - round_down(x) <= unit * (1 + 1e-9)


def test_round_up_array_keeps_shape_and_bounds():
    a = [[3.654454723689756e-06, 1.0], [0.0, 2.5e-12]]
    r = round_up_array(a)
    assert r.shape == (2, 2)
    assert r.tolist() == [[3.655e-06, 1.0], [0.0, 2.5e-12]]
