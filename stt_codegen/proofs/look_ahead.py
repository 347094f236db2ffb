"""The look-ahead variant's claims, proved in SymPy on the deployed expressions.

The deployed pieces (:func:`stt_codegen.tube.look_ahead.look_ahead_point`,
:func:`~stt_codegen.tube.look_ahead.base_command`) and the simulated base's kinematics
(:func:`stt_codegen.runtime.differential_drive.base_rhs`) are printed to SymPy by the
emitter's SymPy printer. Composed, they give the look-ahead point's velocity as a function
of law (13)'s output ``u``: ``p_dot = g(theta) u + w`` with ``g = dp_dot/du`` at zero slip.
The checks (docs/differential-drive.md, "The argument"):

* ``look_ahead.inverse``: with exact wheels ``g(theta) = I`` for every ``theta``: the
  deployed command moves the point exactly as law (13) asks, whatever the heading;
* ``assumption2.differential_drive``: with wheel errors ``delta_R``, ``delta_L`` (symbols),
  the symmetric part of ``g`` has the characteristic polynomial ``(lambda - (1 + m))^2 -
  d^2 s^2`` and the skew part is ``d k [[0, 1], [-1, 0]]`` (symbolically, every heading), so
  ``lambda_min = 1 + m - |d| s``; at the spec's wheel errors it is positive (Assumption
  2) and within the spec's ``[assumptions] input_gain``, as are the skew part and the
  drift (zero).
"""

from __future__ import annotations

import sympy as sp

from ..codegen.emit import sympy_expressions
from ..runtime.differential_drive import base_rhs
from ..spec.loader import Spec
from ..tube.look_ahead import base_command, look_ahead_point
from .check import Check

__all__ = ["assumption2_differential_drive", "point_input_matrix", "look_ahead_inverse"]


def point_input_matrix(axle_offset: sp.Expr, track_width: sp.Expr,
                       errors: tuple[sp.Expr, sp.Expr]) -> tuple[sp.Matrix, sp.Symbol]:
    """``g(theta)`` of the look-ahead point's system under the deployed command.

    Parameters
    ----------
    axle_offset, track_width : sympy.Expr
        ``l`` and ``b``, m (symbols or numbers).
    errors : (sympy.Expr, sympy.Expr)
        The wheels' relative radius errors ``(delta_R, delta_L)``.

    Returns
    -------
    g : sympy.Matrix, shape (2, 2)
        ``d p_dot / d u`` at zero slip, simplified.
    theta : sympy.Symbol
        The heading symbol ``g`` depends on.
    """
    x, y, theta = sp.symbols("x y theta", real=True)
    u = sp.symbols("u1 u2", real=True)
    state = [x, y, theta]
    p, heading = sympy_expressions(look_ahead_point(), {"state": state,
                                                        "axle_offset": [axle_offset]})
    (command,) = sympy_expressions(base_command(), {"heading": list(heading), "u_point": list(u),
                                                    "axle_offset": [axle_offset]})
    (state_dot,) = sympy_expressions(base_rhs(), {
        "state": state, "u": list(command), "wheel_radius_error": list(errors),
        "track_width": [track_width], "slip": [0, 0, 0]})
    p_dot = sp.Matrix(p).jacobian(sp.Matrix(state)) * sp.Matrix(state_dot)
    g = p_dot.jacobian(sp.Matrix(u))
    return g.applyfunc(lambda v: sp.simplify(sp.trigsimp(v))), theta


def look_ahead_inverse() -> Check:
    """``look_ahead.inverse``: the deployed command inverts the base's kinematics.

    Returns
    -------
    Check
        Passed when ``g(theta) = I`` symbolically for exact wheels, any ``l > 0``.
    """
    offset, width = sp.symbols("l b", positive=True)
    g, _ = point_input_matrix(offset, width, (sp.Integer(0), sp.Integer(0)))
    ok = (g - sp.eye(2)).applyfunc(sp.simplify) == sp.zeros(2, 2)
    return Check("look_ahead.inverse", bool(ok),
                 "with exact wheels the look-ahead point moves with u exactly: g(theta) = I "
                 "for every heading and axle offset (symbolic)" if ok else
                 f"g(theta) = {g} is not the identity: the deployed command does not invert "
                 "the base's kinematics", {"g": str(g)})


def assumption2_differential_drive(spec: Spec) -> Check:
    """``assumption2.differential_drive``: the look-ahead point's ``g`` under the spec's
    wheel errors meets Assumption 2 and the spec's ``[assumptions]``.

    Parameters
    ----------
    spec : Spec
        A differential-drive spec (``spec.drive``).

    Returns
    -------
    Check
        With ``lambda_min``, ``lambda_max`` of the symmetric part and the skew norm.
    """
    drive = spec.drive
    offset, width = sp.symbols("l b", positive=True)
    d_r, d_l = sp.symbols("delta_R delta_L", real=True)
    g, _ = point_input_matrix(offset, width, (d_r, d_l))
    m, d = (d_r + d_l) / 2, (d_r - d_l) / 2
    beta = width / (2 * offset)
    s, k = (beta + 1 / beta) / 2, (beta - 1 / beta) / 2
    lam = sp.Symbol("lambda")
    sym, skew = (g + g.T) / 2, (g - g.T) / 2
    polynomial = sp.simplify(sp.expand(sp.trigsimp((sym - lam * sp.eye(2)).det()
                                                   - ((lam - (1 + m)) ** 2 - d ** 2 * s ** 2))))
    skew_error = sp.simplify(skew - d * k * sp.Matrix([[0, 1], [-1, 0]]))
    structure = polynomial == 0 and skew_error == sp.zeros(2, 2)
    values = {offset: drive.axle_offset, width: drive.track_width,
              d_r: drive.wheel_radius_error[0], d_l: drive.wheel_radius_error[1]}
    lam_min = float((1 + m - sp.Abs(d) * s).subs(values))
    lam_max = float((1 + m + sp.Abs(d) * s).subs(values))
    skew_norm = float((sp.Abs(d) * sp.Abs(k)).subs(values))
    a = spec.assumptions
    tol = 1e-9 * max(1.0, lam_max)
    within = (a.input_gain[0] <= lam_min + tol and lam_max <= a.input_gain[1] + tol
              and skew_norm <= a.input_gain_skew + tol)
    passed = bool(structure and lam_min > 0 and within)
    detail = (f"(g + g^T)/2 has the eigenvalues 1 + m -+ |d| s = [{lam_min:.6g}, {lam_max:.6g}] "
              f"and the skew part the norm |d| |k| = {skew_norm:.3g} for every heading "
              "(symbolic, on the deployed command and the base's kinematics)")
    if not structure:
        detail = "the symmetric and skew parts of g(theta) are not the documented ones"
    elif lam_min <= 0:
        detail += ": lambda_min <= 0, Assumption 2 fails (smaller wheel errors, or an axle "
        detail += "offset closer to half the track width)"
    elif not within:
        detail += (f": outside the spec's input_gain {list(a.input_gain)} / skew "
                   f"{a.input_gain_skew:g}")
    return Check("assumption2.differential_drive", passed, detail,
                 {"lambda_min": lam_min, "lambda_max": lam_max, "skew": skew_norm})
