"""verify proves its lemmas on the deployed pieces: the equality checks pass, and a mutated
piece (tube/pieces.py) or plant (runtime/dynamics.py) makes the checks on it fail."""

from __future__ import annotations

import casadi as ca
import pytest
import sympy as sp

from stt_codegen.tube import pieces
from stt_codegen.proofs import assumption, deployed, lemma, transform
from stt_codegen.proofs.adaptive import adaptive_law_checks


def _clear() -> None:
    for name in dir(deployed):
        clear = getattr(getattr(deployed, name), "cache_clear", None)
        if clear is not None:
            clear()


@pytest.fixture
def mutate(monkeypatch):
    """``mutate(module, name, replacement)``: patch, with the deployed caches cleared before
    and after."""
    _clear()

    def apply(module, name, replacement):
        monkeypatch.setattr(module, name, replacement)
        _clear()

    yield apply
    monkeypatch.undo()
    _clear()


@pytest.mark.slow
def test_every_deployed_piece_equals_the_papers_formula():
    checks = deployed.deployed_checks()
    assert [c.name for c in checks] == [
        "deployed.reach", "deployed.bump", "deployed.smooth_max", "deployed.open_bump_sum",
        "deployed.trigger", "deployed.alpha_rate", "deployed.law.n2"]
    assert all(c.passed for c in checks), [str(c) for c in checks if not c.passed]


def test_the_deployed_branches_are_the_papers_expressions():
    t, t_c, x0, target = deployed.T, deployed.T_C, deployed.X0, deployed.TARGET
    assert sp.simplify(deployed.reach_branch()
                       - ((target - x0) * sp.tanh(t / (t_c - t)) + x0)) == 0
    assert deployed.reach_after() == target
    assert deployed.bump_outside(1) == 0 and deployed.bump_outside(-1) == 0


def test_on_domain_refuses_what_the_domain_does_not_decide():
    x = sp.Symbol("x", real=True)
    with pytest.raises(deployed.DomainUndecided):
        deployed.on_domain(sp.Piecewise((1, x < 0), (0, True)))
    w = sp.Symbol("w", positive=True)
    assert deployed.on_domain(sp.Piecewise((1, x < 0), (2, True)), {x: -w}) == 1
    assert deployed.on_domain(sp.Max(x, -80.0), {}, {sp.Integer(-80): 1}) == x


def _progress_not_flat(profile: str, rates: bool = True) -> ca.Function:
    """The tanh segment with ``tanh(elapsed / (gap + 1))``: not 1 at ``t_c``."""
    t, start, end = (ca.SX.sym(n) for n in ("t", "start", "end"))
    before = t < end
    gap = ca.if_else(before, end - t, 1.0)
    p = ca.if_else(before, ca.tanh((t - start) / (gap + 1.0)), 1.0)
    return ca.Function(f"progress_{profile}", [t, start, end], [p, ca.jacobian(p, t)],
                       ["t", "start", "end"], ["p", "p_dot"])


def test_a_mutated_reach_segment_fails_its_checks(mutate):
    mutate(pieces, "progress", _progress_not_flat)
    assert not deployed.check_reach().passed
    assert not lemma.check_reach_continuity(orders=1).passed


def _bump_linear_exponent(rates: bool = True) -> ca.Function:
    """The bump with ``-k |d| / den`` for ``-k d^2 / den`` in the exponent."""
    names = ["t", "start", "end", "center", "radius", "sharpness", "height"]
    t, start, end, center, radius, sharpness, height = (ca.SX.sym(n) for n in names)
    d = t - center
    inside = ca.logic_and(ca.logic_and(t > start, t < end), ca.fabs(d) < radius)
    denom = ca.if_else(inside, (radius - ca.fabs(d)) * (radius + ca.fabs(d)), 1.0)
    exponent = ca.fmax(-sharpness * ca.fabs(d) / denom, -pieces.EXP_ARGUMENT_BOUND)
    y = ca.if_else(inside, height * ca.exp(exponent), 0.0)
    return ca.Function("bump", [t, start, end, center, radius, sharpness, height],
                       [y, ca.jacobian(y, t)], names, ["y", "y_dot"])


def test_a_mutated_bump_fails_its_checks(mutate):
    mutate(pieces, "bump", _bump_linear_exponent)
    assert not deployed.check_bump().passed
    assert not lemma.bump_rate_bound(2.0, 1.0).passed


def _smooth_pieces_without_correction():
    original = _smooth_pieces_without_correction.original()
    a, b, nu = (ca.SX.sym(n) for n in ("a", "b", "nu"))
    wrong = ca.Function("smooth_max", [a, b, nu], [ca.fmax(a, b) + ca.log(2.0) / nu],
                        ["a", "b", "nu"], ["max"])
    return (original[0], wrong, *original[2:])


def test_a_mutated_smooth_max_fails_its_checks(mutate):
    _smooth_pieces_without_correction.original = pieces.smooth_pieces
    mutate(pieces, "smooth_pieces", _smooth_pieces_without_correction)
    assert not deployed.check_smooth_max().passed
    assert not lemma.check_smooth_max().passed


def _conflict_half_trigger(n: int) -> ca.Function:
    rho, beta = ca.SX.sym("rho", 2 * n), ca.SX.sym("beta", 2 * n)
    theta0, mu = ca.SX.sym("theta0"), ca.SX.sym("mu")
    psi = ca.vertcat(beta[n:] - rho[:n], rho[n:] - beta[:n])
    theta = theta0 / (1.0 + ca.exp(2.0 * (psi - mu)))       # half the deployed one
    return ca.Function("conflict", [rho, beta, theta0, mu], [psi, theta],
                       ["rho", "beta", "theta0", "mu"], ["psi", "theta"])


def test_a_mutated_trigger_fails_its_checks(mutate):
    mutate(pieces, "conflict", _conflict_half_trigger)
    assert not deployed.check_trigger().passed


def _trigger_negative(n: int) -> ca.Function:
    rho, beta = ca.SX.sym("rho", 2 * n), ca.SX.sym("beta", 2 * n)
    theta0, mu = ca.SX.sym("theta0"), ca.SX.sym("mu")
    psi = ca.vertcat(beta[n:] - rho[:n], rho[n:] - beta[:n])
    theta = theta0 * ca.tanh(mu - psi)                      # changes sign at psi = mu
    return ca.Function("conflict", [rho, beta, theta0, mu], [psi, theta],
                       ["rho", "beta", "theta0", "mu"], ["psi", "theta"])


def test_a_trigger_that_can_be_negative_fails_nonnegativity(mutate):
    mutate(pieces, "conflict", _trigger_negative)
    checks = {c.name: c for c in adaptive_law_checks(0.5, 1.0, 1.0, 1.0)}
    assert not checks["adaptive.nonnegative"].passed


def _error_transform_half_log(n: int) -> ca.Function:
    x, gamma_l, gamma_u = (ca.SX.sym(name, n) for name in ("x", "gamma_L", "gamma_U"))
    e, _, xi = pieces.error_transform_expression(x, gamma_l, gamma_u)
    return ca.Function("error_transform", [x, gamma_l, gamma_u], [e, ca.log(1.0 + e), xi],
                       ["x", "gamma_L", "gamma_U"], ["e", "epsilon", "xi"])


def test_a_mutated_error_transform_fails_its_checks(mutate):
    mutate(pieces, "error_transform", _error_transform_half_log)
    assert not transform.check_epsilon_jacobian(1).passed
    assert not transform.check_lyapunov_derivative(1).passed
    assert not deployed.check_law(2).passed


def test_a_law_that_is_not_built_from_the_transform_fails(mutate):
    def law_doubled(n: int) -> ca.Function:
        x, gamma_l, gamma_u = (ca.SX.sym(name, n) for name in ("x", "gamma_L", "gamma_U"))
        gain = ca.SX.sym("gain")
        u, inside = pieces.law_expression(x, gamma_l, gamma_u, gain, n)
        return ca.Function("law", [x, gamma_l, gamma_u, gain], [2.0 * u, inside],
                           ["x", "gamma_L", "gamma_U", "gain"], ["u", "inside"])

    mutate(pieces, "law", law_doubled)
    assert not deployed.check_law(2).passed


def test_assumption2_takes_g_from_the_plant_definition(mutate):
    def reversed_robot(model: str, n: int) -> ca.Function:
        x = ca.SX.sym("x", n)
        c, s = ca.cos(x[2]), ca.sin(x[2])
        g = -ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))
        return ca.Function("plant_input_matrix", [x], [g], ["x"], ["g"])

    assert assumption.assumption2_omnidirectional((-1.0, 1.0)).passed
    mutate(assumption, "input_matrix", reversed_robot)
    assert not assumption.assumption2_omnidirectional((-1.0, 1.0)).passed


def test_an_undecidable_piece_is_a_failed_check_not_an_exception(mutate):
    def progress_open(profile: str, rates: bool = True) -> ca.Function:
        t, start, end = (ca.SX.sym(n) for n in ("t", "start", "end"))
        p = ca.if_else(t < 2.0 * end, ca.tanh(t), 1.0)      # 2 t_c: not decided on t < t_c
        return ca.Function(f"progress_{profile}", [t, start, end], [p, ca.jacobian(p, t)],
                           ["t", "start", "end"], ["p", "p_dot"])

    mutate(pieces, "progress", progress_open)
    checks = {c.name: c for c in deployed.deployed_checks()}
    assert not checks["deployed.reach"].passed
    assert "not reduced" in checks["deployed.reach"].detail
