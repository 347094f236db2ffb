"""A python-control ``StateSpace`` as the ``linear`` plant of a spec given as a dict
(``[plant] system``, :meth:`stt_codegen.Spec.from_dict` only): its ``A`` and ``B`` become
the plant's ``a`` and ``g``."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import SpecError, number_text
from .plants import MODEL_KEYS

__all__ = ["with_state_space"]


def with_state_space(data: Mapping[str, Any]) -> Mapping[str, Any]:
    """``data`` with ``plant.system`` (a continuous-time python-control ``StateSpace``
    ``x_dot = A x + B u``, ``y = x``) replaced by ``plant.a = A`` and ``plant.g = B``;
    ``data`` itself where the plant has no ``system``. Raises :class:`SpecError` (field
    ``plant.system``) for another model, ``a`` or ``g`` given too, a discrete-time
    system, an output other than the state (``C = I``, ``D = 0``), or a ``B`` that is not
    square (one input per state)."""
    plant = data.get("plant")
    if not isinstance(plant, Mapping) or "system" not in plant:
        return data
    system = plant["system"]
    field = "plant.system"
    if not all(hasattr(system, k) for k in ("A", "B", "C", "D", "dt")):
        raise SpecError(field, f"must be a control.StateSpace, got {type(system).__name__}")
    owner = MODEL_KEYS["a"]          # the model whose keys a and g a system gives
    if plant.get("model") != owner:
        raise SpecError(field, f'only plant.model = "{owner}" takes a system')
    given = [k for k in ("a", "g") if k in plant]
    if given:
        raise SpecError(field, f"give either system or {'/'.join(given)}, not both")
    if system.dt not in (0, None):
        raise SpecError(field, f"must be continuous-time (dt = 0), got dt = "
                               f"{number_text(float(system.dt))}: give the plant itself, "
                               f"the controller samples it")
    a, b, c, d = (np.asarray(m, dtype=float) for m in (system.A, system.B, system.C, system.D))
    n = a.shape[0]
    if b.shape != (n, n):
        raise SpecError(field, f"B must be {n} x {n} (one input per state), got "
                               f"{b.shape[0]} x {b.shape[1]}")
    if c.shape != (n, n) or not np.array_equal(c, np.eye(n)) or np.any(d != 0.0):
        raise SpecError(field, "the controller measures the state: C must be the identity "
                               "and D zero")
    rest = {k: v for k, v in plant.items() if k != "system"}
    return {**data, "plant": {**rest, "a": a.tolist(), "g": b.tolist()}}
