"""Whether the spec's own plant lies in the class ``verify`` certifies, for both orders.

The sampled checks judge a class of plants (``[assumptions]``, or a second-order model's
second stage); the spec's simulated plant is covered only if it is a member. One check,
:func:`plant_within_assumptions`, compares the model's bounds with the class: for a
first-order model its bounds over the state space
(:func:`~stt_codegen.spec.model_bounds.model_bounds`), for a second-order one ``g = I / m``
and its drift within the velocity bound
(:func:`~stt_codegen.design.certificate.cascade_sampled.model_within_class`).
"""

from __future__ import annotations

from ..rounding import distinct
from ..spec.loader import Spec
from ..spec.model_bounds import model_bounds
from ..spec.plants import plant_entry
from ..design.certificate.cascade_sampled import model_within_class
from ..proofs.check import Check
from ..spec.variants import variant_of

__all__ = ["cascade_within", "first_order_within", "plant_within_assumptions"]


def _not_checked(prefix: str, model: str, verdict: str) -> Check:
    """The membership check of a plant without equations (or simulated on MuJoCo): passed,
    saying it is not checked."""
    return Check(f"{prefix}.plant_within_assumptions", True,
                 f"not checked: the {model} plant runs on MuJoCo, whose equations are not "
                 f"here, so {verdict} holds for it only if it meets the [assumptions]",
                 {"declared_only": True})


def first_order_within(spec: Spec, model: str | None) -> Check:
    """``sampled.plant_within_assumptions`` (role ``plant_within`` of law (13) and the
    look-ahead law, :mod:`~stt_codegen.spec.variants`): the model's bounds over the state
    space within ``spec.assumptions``.

    Parameters
    ----------
    spec : Spec
    model : str or None
        First-order plant model, default the spec's.

    Returns
    -------
    Check
    """
    model = model or spec.plant_model
    # no equations, or a MuJoCo model of the plant: nothing to compare
    if plant_entry(model).declared_bounds or spec.mujoco is not None:
        return _not_checked("sampled", model, "the sampled verdict")
    # only a model that takes [plant] matrices or parameters is evaluated with the spec's
    b = model_bounds(model, spec.state_space.lower, spec.state_space.upper,
                     spec.plant_data(model))
    a = spec.assumptions
    tol = 1e-9
    bad = []
    if b.input_gain[0] < a.input_gain[0] - tol or b.input_gain[1] > a.input_gain[1] + tol:
        bad.append(f"eig((g + g^T)/2) spans [{distinct(b.input_gain[0], a.input_gain[0], 6)}, "
                   f"{distinct(b.input_gain[1], a.input_gain[1], 6)}], outside input_gain "
                   f"{list(a.input_gain)} (tolerance {tol:g})")
    for key in ("input_gain_skew", "input_gain_coupling", "drift_bound"):
        if getattr(b, key) > getattr(a, key) + tol:
            bad.append(f"{key} is {distinct(getattr(b, key), getattr(a, key), 6)} > "
                       f"{getattr(a, key)!r} (tolerance {tol:g})")
    found = {"input_gain": list(b.input_gain), "input_gain_skew": b.input_gain_skew,
             "input_gain_coupling": b.input_gain_coupling, "drift_bound": b.drift_bound}
    return Check(
        "sampled.plant_within_assumptions", not bad,
        f"the {model} model meets the bounds the sampled check uses (eig in "
        f"[{b.input_gain[0]:.6g}, {b.input_gain[1]:.6g}], skew {b.input_gain_skew:.3g}, "
        f"coupling {b.input_gain_coupling:.3g}, max |f| {b.drift_bound:.3g} over the state "
        "space)" if not bad else f"the {model} model is outside the bounds the sampled check "
        "uses, so its verdict does not cover this plant: " + "; ".join(bad), found)


def cascade_within(spec: Spec, model: str | None) -> Check:
    """``cascade.plant_within_assumptions`` (the cascade's role ``plant_within``): the
    second-order model with its parameters in the class ``cascade.sampled`` certifies.

    Parameters
    ----------
    spec : Spec
    model : str or None
        Ignored (the spec's second-order model is judged).

    Returns
    -------
    Check
    """
    if plant_entry(spec.second_order.model).declared_bounds:     # no equations to compare
        return _not_checked("cascade", spec.second_order.model, "the cascade's certificate")
    ok, words, data = model_within_class(spec)
    return Check("cascade.plant_within_assumptions", ok, words, data)


def plant_within_assumptions(spec: Spec, model: str | None = None) -> Check:
    """Whether the spec's plant model meets the bounds the sampled checks judge it by.

    Order 1: ``sampled.plant_within_assumptions``, the model's bounds over the state space
    (eigenvalues of the symmetric part of ``g``, norm of its skew part, row coupling,
    ``max |f|``) within ``spec.assumptions``, to a tolerance of 1e-9. Order 2:
    ``cascade.plant_within_assumptions``, the second-order model with its parameters in the
    class ``cascade.sampled`` certifies.

    Parameters
    ----------
    spec : Spec
        The spec: its state space, plant and class.
    model : str, optional
        First-order plant model, default the spec's (ignored for order 2).

    Returns
    -------
    Check
        PASS when the model is in the class, with the model's figures.
    """
    return variant_of(spec).entry("plant_within")(spec, model)
