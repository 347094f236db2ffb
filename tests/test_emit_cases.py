"""CasADi SX Functions used by the emitter tests (imported by the other test_emit_* files).

Every builder is deterministic (no set or dict keyed by SX) so that the determinism
test can rebuild them in a subprocess.
"""

from __future__ import annotations

from typing import Callable, Dict, List

import casadi as ca

from stt_codegen.codegen.emit import count_operations


def smooth_max() -> ca.Function:
    """Shifted smooth max with sharpness ``nu`` as an input."""
    a, b, nu = ca.SX.sym("a"), ca.SX.sym("b"), ca.SX.sym("nu")
    m = ca.fmax(a, b) + ca.log1p(ca.exp(-nu * ca.fabs(a - b))) / nu
    return ca.Function("smooth_max", [a, b, nu], [m], ["a", "b", "nu"], ["m"])


def smooth_max_min_const() -> ca.Function:
    """Smooth max and min of vectors with a constant ``nu = 20`` (division by a constant)."""
    a, b = ca.SX.sym("a", 3), ca.SX.sym("b", 3)
    nu = 20.0
    mx = ca.fmax(a, b) + ca.log1p(ca.exp(-nu * ca.fabs(a - b))) / nu
    mn = ca.fmin(a, b) - ca.log1p(ca.exp(-nu * ca.fabs(a - b))) / nu
    return ca.Function("smooth_max_min", [a, b], [mx, mn], ["a", "b"], ["max", "min"])


def if_else_nan_branch() -> ca.Function:
    """``if_else`` whose untaken branch is NaN or infinite (log/sqrt/division)."""
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    r1 = ca.if_else(x > 0, ca.log(x), ca.sqrt(-x))
    r2 = ca.if_else(ca.logic_and(x >= 0, y != 0), x / y, ca.log(x - 1))
    r3 = ca.if_else(ca.logic_or(x < -1, ca.logic_not(y)), ca.atanh(x), y ** 1.5)
    return ca.Function("if_else_nan", [x, y], [ca.vertcat(r1, r2, r3)], ["x", "y"], ["r"])


def tanh_time() -> ca.Function:
    """``tanh(t/(tc - t))`` raw (divides by zero at ``tc``) and with its ``t >= tc`` branch."""
    t, tc = ca.SX.sym("t"), ca.SX.sym("tc")
    raw = ca.tanh(t / (tc - t))
    safe = ca.if_else(t < tc, ca.tanh(t / (tc - t)), 1.0)
    dsafe = ca.jacobian(safe, t)
    return ca.Function("tanh_time", [t, tc], [raw, safe, dsafe], ["t", "tc"], ["raw", "s", "s_dot"])


def tanh_time_const() -> ca.Function:
    """``tanh(t/(9 - t))`` with a constant ``tc`` (as in the paper's case study)."""
    t = ca.SX.sym("t")
    return ca.Function("tanh_time9", [t], [ca.tanh(t / (9.0 - t))], ["t"], ["s"])


def jacobians() -> ca.Function:
    """Jacobians (sparse) of a small vector field with respect to a vector."""
    x = ca.SX.sym("x", 3)
    p = ca.SX.sym("p", 2)
    f = ca.vertcat(
        ca.fmax(x[0], p[0]) + ca.log1p(ca.exp(-5 * ca.fabs(x[0] - p[0]))) / 5,
        ca.tanh(x[1] / (p[1] - x[1])) * x[2],
        ca.atanh(x[2] / 2) + x[0] * x[1] ** 2,
        ca.sin(x[0]) * ca.cos(x[1]) + ca.exp(-x[2] ** 2),
    )
    jx = ca.jacobian(f, x)
    jp = ca.jacobian(f, p)
    hess = ca.hessian(f[3], x)[0]
    return ca.Function("jacobians", [x, p], [f, jx, jp, hess], ["x", "p"], ["f", "jx", "jp", "hess"])


def multi_output_sparse() -> ca.Function:
    """Several outputs: sparse matrix, sparsified vector, dense matrix, constant, copy."""
    x = ca.SX.sym("x", 2)
    y = ca.SX.sym("y", 2, 2)
    diag = ca.diag(ca.vertcat(ca.exp(x[0]), ca.log(x[1])))
    sparse_vec = ca.sparsify(ca.vertcat(0, x[0] * x[1], 0, ca.sqrt(x[1])))
    dense = ca.horzcat(y @ x, y.T @ x, ca.fabs(y[:, 0]) - x)
    lower = ca.tril(y * x[0])
    const = ca.SX(ca.DM([[1.5, -0.0], [float("inf"), 0.1]]))
    return ca.Function(
        "multi_out",
        [x, y],
        [diag, sparse_vec, dense, lower, const, x],
        ["x", "y"],
        ["diag", "sparse_vec", "dense", "lower", "const", "copy"],
    )


def newton_unrolled(n: int = 2, iterations: int = 8) -> ca.Function:
    """Backward-Euler step of ``alpha_dot = theta/(psi + alpha)^2 - kappa alpha``.

    ``psi`` is a circumvent bump kept piecewise (``if_else``); the implicit equation is
    solved by an unrolled Newton loop with the exact (diagonal) derivative.
    """
    t, dt = ca.SX.sym("t"), ca.SX.sym("dt")
    alpha = ca.SX.sym("alpha", n)
    theta, kappa, k, m, r = 0.01, 5.0, 0.01, 4.0, 1.5
    d2 = (t + dt - m) ** 2
    bump = ca.if_else(d2 < r ** 2, ca.exp(-k * d2 / (r ** 2 - d2)), 0)
    psi = 0.5 + bump * ca.DM([1.0, 2.0][:n] + [1.0] * max(0, n - 2))
    a = alpha
    for _ in range(iterations):
        g = a - alpha - dt * (theta / (psi + a) ** 2 - kappa * a)
        dg = 1 - dt * (-2 * theta / (psi + a) ** 3 - kappa)
        a = a - g / dg
    return ca.Function("alpha_step", [t, dt, alpha], [a], ["t", "dt", "alpha"], ["alpha_next"])


CASES: Dict[str, Callable[[], ca.Function]] = {
    "smooth_max": smooth_max,
    "smooth_max_min_const": smooth_max_min_const,
    "if_else_nan_branch": if_else_nan_branch,
    "tanh_time": tanh_time,
    "tanh_time_const": tanh_time_const,
    "jacobians": jacobians,
    "multi_output_sparse": multi_output_sparse,
    "newton_unrolled": newton_unrolled,
}


def all_functions() -> List[ca.Function]:
    """Every case, in the order of :data:`CASES`."""
    return [build() for build in CASES.values()]


def test_cases_are_sx_and_cover_the_special_ops() -> None:
    ops: Dict[str, int] = {}
    for fn in all_functions():
        assert fn.is_a("SXFunction")
        for op, n in count_operations(fn).by_op.items():
            ops[op] = ops.get(op, 0) + n
    for op in ("fmax", "fmin", "log1p", "exp", "fabs", "tanh", "if_else_zero", "div",
               "log", "sqrt", "atanh", "lt", "le", "ne", "not", "and", "or", "const",
               "sq", "constpow", "twice"):
        assert op in ops, op
