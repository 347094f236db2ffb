"""``[assumptions]``: the plant bounds ``verify`` judges against, from the model and the spec.

The spec names a plant model (``[plant] model``); :mod:`.model_bounds` gives what that
model implies over the state space ``X``. ``[assumptions]`` may add what the model leaves
open (the disturbance) and may widen a bound (a margin for a real plant that differs from
the model), but it may not claim a bound the model violates: ``verify`` never judges a
plant against assumptions its own model breaks. The rules (docs/sampled-data.md,
"What the spec declares"; docs/decisions.md, decision 18):

* a key not declared takes the model's value (``disturbance_bound``: ``sqrt(n)`` times
  ``plant.disturbance_amplitude``);
* a declared bound that contains the model's is used as declared, and reported (a note);
* a declared bound the model violates somewhere on ``X`` is a ``SpecError`` naming the
  key, with the model's value and where the model attains it;
* ``input_gain_coupling`` not declared but ``input_gain`` or ``input_gain_skew``
  declared: the value those imply, ``(g_max - g_min)/2 + skew``, as before the models
  had bounds; a declared coupling above that implied value is lowered to it;
* the model's block structure of ``g`` is kept only while no bound on ``g`` is declared;
* ``input_gain_lipschitz`` and ``drift_lipschitz`` (one value per state) not declared: the
  model's own while no bound on ``g`` (respectively ``drift_bound``) is declared, else
  none (the class's ``g`` or ``f`` may jump, as for a plant the model does not describe);
  declared: one per state, never below the model's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

from ..errors import SpecError, number_text
from .model_bounds import ModelBounds

__all__ = ["Assumptions", "G_KEYS", "LIPSCHITZ_KEYS", "combine_assumptions"]

#: The keys that bound ``g`` (the others bound ``f`` and ``w``).
G_KEYS = ("input_gain", "input_gain_skew", "input_gain_coupling")
#: The keys that bound how fast ``g`` and ``f`` change with the state.
LIPSCHITZ_KEYS = ("input_gain_lipschitz", "drift_lipschitz")
#: Relative slack when comparing a declared bound with the model's (a value printed to
#: many digits and typed back, or the model's outward rounding, is not a contradiction).
CONTRADICTION_TOL = 1e-9


@dataclass(frozen=True)
class Assumptions:
    """The bounds on the plant (1) that ``verify``'s sampled check proves the controller for.

    The plant is ``x_dot = f(x) + g(x) u + w``; every bound holds uniformly over the state
    space ``X`` (and ``w`` over time). They come from the spec's plant model and its
    ``[assumptions]`` (:func:`combine_assumptions`). Used to derive the default gain ``k``
    of law (13) (:mod:`stt_codegen.design.gain`) and by the sampled-data check
    (:mod:`stt_codegen.design.certificate.sampled`); the controller itself never sees them.

    Attributes
    ----------
    input_gain : tuple of float, (g_min, g_max)
        Bounds on the eigenvalues of the symmetric part ``(g + g^T) / 2`` of ``g(x)``;
        Assumption 2 asks ``g_min > 0``.
    input_gain_skew : float
        Bound on the spectral norm of the skew part ``(g - g^T) / 2``.
    input_gain_coupling : float
        Bound on the Euclidean norm of the off-diagonal part of every row of ``g(x)``:
        how strongly one input drives the other states; at most
        ``(g_max - g_min) / 2 + input_gain_skew``, which the two above imply.
    drift_bound : float
        Bound on the Euclidean norm ``|f(x)|``, state units per second.
    disturbance_bound : float
        Bound on the Euclidean norm ``|w(t)|``, state units per second.
    declared : tuple of str
        The keys the spec set explicitly (the others come from the model or defaults).
    model : str
        The plant model whose bounds fill the keys not declared (``""`` for bounds built
        by hand, e.g. in a study: then nothing is known beyond the numbers).
    blocks : tuple of tuple of int
        A partition of the state indices in which ``g(x)`` is block diagonal (an input of
        one block never moves a state of another); ``()``: not known, see
        :meth:`coupled_blocks`.
    notes : tuple of str
        Declared bounds wider than the model's, in words (reported by ``verify``).
    input_gain_lipschitz : tuple of float or None
        Per state ``j``, ``L_j`` with ``|g(x) - g(y)|_2 <= sum_j L_j |x_j - y_j|`` (units of
        ``g`` per state unit); ``None``: not bounded, ``g`` may jump between any members.
    drift_lipschitz : tuple of float or None
        Per state, ``L_j`` with ``|f(x) - f(y)| <= sum_j L_j |x_j - y_j|`` (per second);
        ``None``: ``f`` may jump.
    input_gain_turn : tuple of float or None
        ``(a, b)``: between the instant a held command was computed and any instant it
        acts, the plant's ``g`` is ``R(phi) g_k`` with ``g_k`` within the bounds above,
        ``R`` a rotation of the plane (two states) and ``|phi_dot| <= a |u| + b`` (rad/s,
        ``|u|`` the Euclidean norm of the acting command): a differential-drive base turns
        its look-ahead point's ``g`` with its heading (docs/differential-drive.md).
        ``None``: ``g`` does not turn with the command.
    """

    input_gain: tuple[float, float] = (1.0, 1.0)
    input_gain_skew: float = 0.0
    input_gain_coupling: float = 0.0
    drift_bound: float = 0.0
    disturbance_bound: float = 0.0
    declared: tuple[str, ...] = ()
    model: str = ""
    blocks: tuple[tuple[int, ...], ...] = ()
    notes: tuple[str, ...] = ()
    input_gain_lipschitz: tuple[float, ...] | None = None
    drift_lipschitz: tuple[float, ...] | None = None
    input_gain_turn: tuple[float, float] | None = None

    def coupled_blocks(self, n: int) -> tuple[tuple[int, ...], ...]:
        """The blocks of ``g`` for ``n`` states: :attr:`blocks` when known; else one block
        of all states, or one per state when ``input_gain_coupling`` is 0 (then ``g`` is
        diagonal)."""
        if self.blocks:
            return self.blocks
        if self.input_gain_coupling == 0.0:
            return tuple((i,) for i in range(n))
        return (tuple(range(n)),)

    @property
    def g_from_model(self) -> bool:
        """``g``'s bounds are the model's own (no key of :data:`G_KEYS` declared)."""
        return bool(self.model) and not any(k in self.declared for k in G_KEYS)

    @property
    def drift_from_model(self) -> bool:
        """``drift_bound`` is the model's own."""
        return bool(self.model) and "drift_bound" not in self.declared


def _contradiction(field: str, declared: float, model: float, bounds: ModelBounds,
                   key: str, declared_above: bool) -> SpecError:
    side = "above" if declared_above else "below"
    fix = "at most" if declared_above else "at least"
    return SpecError(field, f"{declared!r} is {side} {model:.9g}, which the {bounds.model} "
                            f"model reaches on the state space ({bounds.words(key)}): the "
                            f"model violates it; declare {fix} {model:.9g}, drop the key "
                            f"(the model's bound is used), or {bounds.remedy}")


def _tighter(declared: float, model: float, upper: bool) -> bool:
    """Whether ``declared`` is tighter than ``model`` beyond the tolerance."""
    slack = CONTRADICTION_TOL * max(1.0, abs(model))
    return declared < model - slack if upper else declared > model + slack


def combine_assumptions(bounds: ModelBounds, declared: Mapping[str, object], n: int,
                        amplitude: float, prefix: str = "assumptions") -> Assumptions:
    """The :class:`Assumptions` of a plant model and the keys a spec declares.

    Parameters
    ----------
    bounds : ModelBounds
        What the spec's plant model implies over the state space
        (:func:`~.model_bounds.model_bounds`).
    declared : mapping
        The declared ``[assumptions]`` keys and their values (``input_gain`` a pair of
        floats, the others floats), already checked by the schema (finite, signs).
    n : int
        State dimension.
    amplitude : float
        ``plant.disturbance_amplitude`` (the default ``disturbance_bound`` is
        ``sqrt(n)`` times it, unless the model implies its own,
        ``bounds.disturbance_bound``).
    prefix : str
        Field prefix for errors.

    Returns
    -------
    Assumptions
        The bounds the design uses: a declared bound where given (never tighter than the
        model's: that is refused), the model's otherwise; its notes name each declared value
        wider than the model's.

    Raises
    ------
    SpecError
        ``input_gain`` not ``0 < g_min <= g_max``, or a declared bound the model violates
        (the field names the key; the reason gives the model's value).
    """
    notes = []
    g_min, g_max = bounds.input_gain
    if "input_gain" in declared:
        d_min, d_max = (float(v) for v in declared["input_gain"])  # type: ignore[union-attr]
        field = f"{prefix}.input_gain"
        if d_min <= 0:
            raise SpecError(field, f"g_min = {d_min!r} must be positive (Assumption 2)")
        if d_min > d_max:
            raise SpecError(field, f"g_min = {d_min!r} exceeds g_max = {d_max!r}")
        if _tighter(d_min, g_min, upper=False):
            raise _contradiction(field, d_min, g_min, bounds, "input_gain", declared_above=True)
        if _tighter(d_max, g_max, upper=True):
            raise _contradiction(field, d_max, g_max, bounds, "input_gain", declared_above=False)
        if (d_min, d_max) != (g_min, g_max):
            notes.append(f"input_gain [{d_min:g}, {d_max:g}] is wider than the "
                         f"{bounds.model} model's [{g_min:.6g}, {g_max:.6g}]")
        g_min, g_max = min(d_min, g_min), max(d_max, g_max)
    values = {"input_gain_skew": bounds.input_gain_skew,
              "input_gain_coupling": bounds.input_gain_coupling,
              "drift_bound": bounds.drift_bound}
    for key, model_value in list(values.items()):
        if key not in declared:
            continue
        value = float(declared[key])  # type: ignore[arg-type]
        if _tighter(value, model_value, upper=True):
            raise _contradiction(f"{prefix}.{key}", value, model_value, bounds, key,
                                 declared_above=False)
        if value != model_value:
            notes.append(f"{key} {value:g} is above the {bounds.model} model's "
                         f"{model_value:.6g}")
        values[key] = max(value, model_value)
    skew = values["input_gain_skew"]
    implied = 0.5 * (g_max - g_min) + skew
    g_declared = any(k in declared for k in G_KEYS)
    if "input_gain_coupling" in declared:
        coupling = min(values["input_gain_coupling"], implied)
    elif g_declared:
        coupling = implied                 # what the declared bounds imply, as before
    else:
        coupling = bounds.input_gain_coupling
    if g_declared:
        blocks = (tuple(range(n)),) if coupling > 0 else tuple((i,) for i in range(n))
    else:
        blocks = bounds.blocks
    own = (math.sqrt(n) * amplitude if bounds.disturbance_bound is None
           else bounds.disturbance_bound)
    if "disturbance_bound" in declared:
        disturbance = float(declared["disturbance_bound"])  # type: ignore[arg-type]
        if bounds.disturbance_bound is not None and _tighter(disturbance, own, upper=True):
            raise _contradiction(f"{prefix}.disturbance_bound", disturbance, own, bounds,
                                 "disturbance_bound", declared_above=False)
    else:
        disturbance = own
    lipschitz = {
        "input_gain_lipschitz": (bounds.input_gain_lipschitz, g_declared),
        "drift_lipschitz": (bounds.drift_lipschitz, "drift_bound" in declared)}
    rates = {key: _lipschitz(key, model_value, replaced, declared, n, bounds, prefix, notes)
             for key, (model_value, replaced) in lipschitz.items()}
    order = ("input_gain", "input_gain_skew", "input_gain_coupling", "drift_bound",
             "disturbance_bound", *LIPSCHITZ_KEYS)
    return Assumptions((g_min, g_max), skew, coupling, values["drift_bound"], disturbance,
                       tuple(k for k in order if k in declared), bounds.model, blocks,
                       tuple(notes), rates["input_gain_lipschitz"], rates["drift_lipschitz"],
                       bounds.input_gain_turn)


def _lipschitz(key: str, model_value: tuple[float, ...] | None, replaced: bool,
               declared: Mapping[str, object], n: int, bounds: ModelBounds, prefix: str,
               notes: list) -> tuple[float, ...] | None:
    """A Lipschitz bound of :data:`LIPSCHITZ_KEYS`: declared (one per state, never below
    the model's), else the model's unless the bound it qualifies was declared."""
    if key not in declared:
        return None if replaced else model_value
    field = f"{prefix}.{key}"
    value = tuple(float(v) for v in declared[key])  # type: ignore[union-attr]
    if len(value) != n:
        raise SpecError(field, f"has {len(value)} entries; one per state ({n}) is needed")
    if model_value is not None:
        for j, (v, m) in enumerate(zip(value, model_value)):
            if _tighter(v, m, upper=True):
                raise _contradiction(f"{field}[{j}]", v, m, bounds, key, declared_above=False)
        if value != model_value:
            shown = [", ".join(number_text(v) for v in vs) for vs in (value, model_value)]
            notes.append(f"{key} [{shown[0]}] is above the {bounds.model} model's "
                         f"[{shown[1]}]")
        value = tuple(max(v, m) for v, m in zip(value, model_value))
    return value
