"""The plants the sampled check covers, with their bounds on every sampling interval.

The check needs, on each interval ``[t_k, t_{k+1}]``, bounds of ``g`` and ``f`` that hold
wherever ``x`` can be on it. By induction (docs/sampled-data.md) ``x`` stays in the tube,
so a bound over the tube's outer enclosure on that interval (intersected with the state
space) is enough. For bounds the spec declares (or that a study builds by hand), the value
over ``X`` is all there is. For bounds that come from the spec's plant model, the model is
evaluated again on the tube: the omnidirectional robot's ``g = R(x3)`` on the heading range
of the tube on the interval, the ``linear`` model's drift ``|a x + c|`` on the tube's box.
Both are the model's own numbers, never tighter than the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .report import Enclosure
from ...spec.assumptions import Assumptions
from ...spec.loader import LinearPlant, Spec
from ...spec.model_bounds import EXACT_DRIFT_DIMENSIONS, model_bounds
from ...spec.plants import PLANTS

__all__ = ["PlantClass", "IntervalBounds", "plant_class"]


@dataclass(frozen=True)
class IntervalBounds:
    """Bounds of the plant on each sampling interval, arrays of shape (K,).

    Attributes
    ----------
    g_min, g_max : ndarray
        Eigenvalue range of the symmetric part of ``g``.
    skew : ndarray
        Norm of the skew part of ``g``.
    coupling : ndarray
        Norm of the off-diagonal part of a row of ``g``.
    push : ndarray
        ``drift_bound + disturbance_bound``, state units per second.
    refined : tuple of str
        The bounds taken from the model on the tube (empty: uniform over ``X``).
    """

    g_min: np.ndarray
    g_max: np.ndarray
    skew: np.ndarray
    coupling: np.ndarray
    push: np.ndarray
    refined: tuple[str, ...] = ()


@dataclass(frozen=True)
class PlantClass:
    """Declared or model bounds (:class:`~stt_codegen.spec.assumptions.Assumptions`), and,
    when they come from a plant model, what is needed to evaluate the model on the tube.

    Attributes
    ----------
    assumptions : Assumptions
        The bounds on ``g``, ``f`` and ``w``.
    lower, upper : tuple of float or None
        The state space ``X`` (``None``: no model evaluation).
    linear : LinearPlant or None
        The ``linear`` model's matrices.
    """

    assumptions: Assumptions
    lower: tuple[float, ...] | None = None
    upper: tuple[float, ...] | None = None
    linear: LinearPlant | None = None

    def on_intervals(self, enclosure: Enclosure, count: int) -> IntervalBounds:
        """The bounds on the first ``count`` intervals of ``enclosure``.

        Parameters
        ----------
        enclosure : Enclosure
            The tube's enclosure per sampling interval
            (:func:`~stt_codegen.design.certificate.enclose_tube`); ``lower_min`` and
            ``upper_max`` bound the tube from outside.
        count : int
        """
        a = self.assumptions
        ones = np.ones(count)
        g_min, g_max = a.input_gain[0] * ones, a.input_gain[1] * ones
        skew, coupling = a.input_gain_skew * ones, a.input_gain_coupling * ones
        drift = a.drift_bound * ones
        refined: list[str] = []
        model = a.model
        if self.lower is not None and self.upper is not None and model in PLANTS:
            lo = np.maximum(enclosure.lower_min[:count], np.array(self.lower))
            hi = np.minimum(enclosure.upper_max[:count], np.array(self.upper))
            if a.g_from_model and PLANTS[model].gain_varies:
                for k, (l_k, h_k) in enumerate(zip(lo.tolist(), hi.tolist())):
                    b = model_bounds(model, l_k, h_k)
                    g_min[k], g_max[k] = b.input_gain
                    skew[k], coupling[k] = b.input_gain_skew, b.input_gain_coupling
                refined += ["input_gain", "input_gain_skew", "input_gain_coupling"]
            if (a.drift_from_model and PLANTS[model].drift_varies and self.linear is not None
                    and any(v != 0.0 for row in self.linear.a for v in row)
                    and len(self.lower) <= min(6, EXACT_DRIFT_DIMENSIONS)):
                for k, (l_k, h_k) in enumerate(zip(lo.tolist(), hi.tolist())):
                    drift[k] = model_bounds(model, l_k, h_k, self.linear).drift_bound
                refined.append("drift_bound")
            # never looser than over X (the tube lies in X; rounding aside)
            g_min = np.maximum(g_min, a.input_gain[0])
            g_max = np.minimum(g_max, a.input_gain[1])
            skew = np.minimum(skew, a.input_gain_skew)
            coupling = np.minimum(coupling, a.input_gain_coupling)
            drift = np.minimum(drift, a.drift_bound)
        return IntervalBounds(g_min, g_max, skew, coupling, drift + a.disturbance_bound,
                              tuple(refined))


def plant_class(spec: Spec, assumptions: Assumptions | None = None) -> PlantClass:
    """The plant class of a spec: its assumptions and, if they come from its plant model,
    the model (evaluated on the tube per interval).

    Parameters
    ----------
    spec : Spec
        The spec: its assumptions, plant model and state space.
    assumptions : Assumptions, optional
        Instead of ``spec.assumptions`` (then no model evaluation unless its ``model`` is
        the spec's).

    Returns
    -------
    PlantClass
        The class the sampled check takes its bounds from, per interval.
    """
    a = spec.assumptions if assumptions is None else assumptions
    if not a.model or a.model != spec.plant_model:
        return PlantClass(a)
    return PlantClass(a, spec.state_space.lower, spec.state_space.upper, spec.linear_plant)
