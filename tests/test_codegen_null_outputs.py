"""NULL output pointers: every output whose pointer is not NULL is written.

The header promises, on INVALID_INPUT, ``u = 0``, ``alpha_next = alpha`` (non-finite
entries 0, ``alpha`` NULL: 0) and ``gamma_* = 0`` "when the pointers allow". With one
output pointer NULL, ``P_step`` and ``P_tube`` left the other output unwritten. Outputs
are pre-filled with NaN, so an output left unwritten fails.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import designed
from codegen_helpers import COMPILERS, built

from stt_codegen.tube import reference as R

CASE = "omnirobot-s1"
INVALID = 2

pytestmark = pytest.mark.skipif(not COMPILERS, reason="no C compiler (Debian: gcc, clang)")


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    return str(tmp_path_factory.mktemp("null-outputs"))


def _inputs(design):
    t = 0.5 * design.prescribed_time
    psi = R.conflict_distance(design, np.array([t]))[0]
    alpha = np.maximum(0.0, -psi + 1e-2) + 0.125
    g_l, g_u, _, _ = R.adaptive_tube(design, np.array([t]), alpha[None, :])
    return (g_l[0] + g_u[0]) / 2, t, 1.0 / design.rate_hz, alpha


def _nan(lib, size):
    return lib.arr(np.full(size, math.nan))


@pytest.mark.parametrize("precision", ["double", "single"])
def test_step_writes_alpha_next_when_u_is_null(precision, root):
    _, design, _ = designed(CASE)
    n = design.dimension
    lib = built(CASE, precision, COMPILERS[0], root)
    x, t, dt, alpha = _inputs(design)
    a = lib.arr(alpha)
    a[1] = math.inf  # a non-finite entry is replaced by 0
    nxt = _nan(lib, 2 * n)
    assert lib.f["step"](lib.ptr(lib.arr(x)), t, dt, lib.ptr(a), None, lib.ptr(nxt)) == INVALID
    expected = a.copy()
    expected[1] = 0.0
    assert np.array_equal(nxt, expected)
    # in place: alpha_next == alpha
    a2 = lib.arr(alpha)
    assert lib.f["step"](lib.ptr(lib.arr(x)), t, dt, lib.ptr(a2), None, lib.ptr(a2)) == INVALID
    assert np.array_equal(a2, lib.arr(alpha))
    # alpha NULL: alpha_next = 0
    nxt = _nan(lib, 2 * n)
    assert lib.f["step"](lib.ptr(lib.arr(x)), t, dt, None, None, lib.ptr(nxt)) == INVALID
    assert np.array_equal(nxt, np.zeros(2 * n))


@pytest.mark.parametrize("precision", ["double", "single"])
def test_step_writes_u_when_alpha_next_is_null(precision, root):
    _, design, _ = designed(CASE)
    lib = built(CASE, precision, COMPILERS[0], root)
    x, t, dt, alpha = _inputs(design)
    u = _nan(lib, design.dimension)
    assert lib.f["step"](lib.ptr(lib.arr(x)), t, dt, lib.ptr(lib.arr(alpha)), lib.ptr(u),
                         None) == INVALID
    assert np.array_equal(u, np.zeros(design.dimension))


@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("missing", [0, 1])
def test_tube_zeroes_every_other_output(precision, missing, root):
    _, design, _ = designed(CASE)
    n = design.dimension
    lib = built(CASE, precision, COMPILERS[0], root)
    _, t, _, alpha = _inputs(design)
    outs = [_nan(lib, n) for _ in range(4)]
    ptrs = [lib.ptr(v) for v in outs]
    ptrs[missing] = None
    assert lib.f["tube"](t, lib.ptr(lib.arr(alpha)), *ptrs) == INVALID
    for k, v in enumerate(outs):
        if k != missing:
            assert np.array_equal(v, np.zeros(n)), k
