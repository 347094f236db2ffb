"""NULL output pointers: every output whose pointer is not NULL is written, every variant.

The header promises, on INVALID_INPUT, ``u = 0``, ``alpha_next = alpha`` (non-finite
entries 0, ``alpha`` NULL: 0) and every other output 0 "when the pointers allow". With one
output pointer NULL, ``P_step`` and ``P_tube`` once left the other output unwritten.
Outputs are pre-filled with NaN, so an output left unwritten fails. The functions and
their outputs are the header's own (:class:`hard_helpers.HardCase`), one bundled case per
controller variant.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from codegen_helpers import COMPILERS
from hard_helpers import OPTIONAL_OUTPUTS, c_api, hard_case, variant_params

from stt_codegen.tube import reference as R

pytestmark = pytest.mark.skipif(not COMPILERS, reason="no C compiler (Debian: gcc, clang)")


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    return str(tmp_path_factory.mktemp("null-outputs"))


def _inputs(case):
    """``{"x", "t", "dt", "alpha"}`` inside the domain: the tube's centre at ``t_c / 2``."""
    design = case.tube
    t = 0.5 * design.prescribed_time
    psi = R.conflict_distance(design, np.array([t]))[0]
    alpha = np.maximum(0.0, -psi + 1e-2) + 0.125
    g_l, g_u, _, _ = R.adaptive_tube(design, np.array([t]), alpha[None, :])
    return {"x": case.state_at((g_l[0] + g_u[0]) / 2), "t": t, "dt": 1.0 / design.rate_hz,
            "alpha": alpha}


@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("variant", variant_params())
def test_step_writes_alpha_next_when_u_is_null(variant, precision, root):
    case = hard_case(variant)
    lib = c_api(case, precision, COMPILERS[0], root)
    invalid = case.statuses["INVALID_INPUT"]
    given = _inputs(case)
    x = lib.arr(given["x"])
    a = lib.arr(given["alpha"])
    a[1] = math.inf  # a non-finite entry is replaced by 0
    nxt = lib.nan("N_ALPHA")
    assert lib.call("step", x=x, t=given["t"], dt=given["dt"], alpha=a, u=None,
                    alpha_next=nxt) == invalid
    expected = a.copy()
    expected[1] = 0.0
    assert np.array_equal(nxt, expected)
    # in place: alpha_next == alpha
    a2 = lib.arr(given["alpha"])
    assert lib.call("step", x=x, t=given["t"], dt=given["dt"], alpha=a2, u=None,
                    alpha_next=a2) == invalid
    assert np.array_equal(a2, lib.arr(given["alpha"]))
    # alpha NULL: alpha_next = 0
    nxt = lib.nan("N_ALPHA")
    assert lib.call("step", x=x, t=given["t"], dt=given["dt"], alpha=None, u=None,
                    alpha_next=nxt) == invalid
    assert np.array_equal(nxt, np.zeros(case.size("N_ALPHA")))


@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("variant", variant_params())
def test_every_other_output_is_written_when_one_is_null(variant, precision, root):
    """For every API function and each of its required outputs set to NULL: INVALID_INPUT
    and every other output written (``alpha_next = alpha``, the others 0)."""
    case = hard_case(variant)
    lib = c_api(case, precision, COMPILERS[0], root)
    invalid = case.statuses["INVALID_INPUT"]
    given = {k: (lib.arr(v) if k in ("x", "alpha") else v) for k, v in _inputs(case).items()}
    tried = 0
    for name, args in case.functions.items():
        outs = [a for a in args if a.kind == "out"]
        for missing in outs:
            if missing.name in OPTIONAL_OUTPUTS:
                continue
            buffers = {a.name: None if a is missing else lib.nan(a.size) for a in outs}
            assert lib.call(name, **given, **buffers) == invalid, (name, missing.name)
            for a in outs:
                if a is missing:
                    continue
                want = given["alpha"] if a.name == "alpha_next" else np.zeros(case.size(a.size))
                assert np.array_equal(buffers[a.name], want), (name, missing.name, a.name)
            tried += 1
    assert tried >= len(case.functions)        # every function has a required output


@pytest.mark.parametrize("precision", ["double", "single"])
@pytest.mark.parametrize("variant", variant_params())
def test_optional_outputs_may_be_null(variant, precision, root):
    """``gamma_L_dot``, ``gamma_U_dot`` NULL: OK, and the bounds are those of the full call."""
    case = hard_case(variant)
    lib = c_api(case, precision, COMPILERS[0], root)
    given = _inputs(case)
    a = lib.arr(given["alpha"])
    full = {name: lib.nan("N") for name in ("gamma_L", "gamma_U", "gamma_L_dot", "gamma_U_dot")}
    part = {"gamma_L": lib.nan("N"), "gamma_U": lib.nan("N"), "gamma_L_dot": None,
            "gamma_U_dot": None}
    ok = case.statuses["OK"]
    assert lib.call("tube", t=given["t"], alpha=a, **full) == ok
    assert lib.call("tube", t=given["t"], alpha=a, **part) == ok
    for name in ("gamma_L", "gamma_U"):
        assert np.array_equal(part[name], full[name]) and np.all(np.isfinite(full[name]))
