"""Generated files do not depend on the CPU: numpy's SIMD kernels, and rounding to a few digits.

numpy picks ``exp``/``log``/``tanh`` kernels at run time from the CPU's features, and they
differ in the last bits. The generator rounds what such kernels feed into a generated file
(:mod:`stt_codegen.rounding`), and the oracle's printed values use libm. Here the committed
``generated/`` is regenerated with numpy limited to its baseline kernels
(``NPY_DISABLE_CPU_FEATURES`` naming every feature numpy dispatches to on this machine), as
on a CPU without them; ``.ci/run`` does the same, and with the oldest numpy allowed.
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


def _dispatched() -> str:
    out = subprocess.run([sys.executable, str(REPO / ".ci" / "numpy-dispatched")],
                         capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_generated_is_the_same_with_numpys_baseline_kernels():
    features = _dispatched()
    if not features:
        pytest.skip("numpy dispatches to no SIMD feature on this machine: its kernels are "
                    "already the baseline's")
    env = dict(os.environ, NPY_DISABLE_CPU_FEATURES=features)
    done = subprocess.run([sys.executable, "-m", "stt_codegen.cli", "check"], env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, (features, done.stdout[-3000:], done.stderr[-2000:])
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
