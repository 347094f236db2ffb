"""The one registry of the provers the design asks for and ``verify`` supplies.

The design accepts a tube only with a proof built by :mod:`stt_codegen.verify` (the
peak input of law (13) under ``[actuator]``, :data:`INPUT_BOUND`; the sampled cascade's
certificate of a stage, :data:`CASCADE_CERTIFICATE`), which builds on the design and so
cannot be imported by it: :mod:`stt_codegen.verify` registers each prover with
:func:`register_prover` when the package is loaded (``import stt_codegen`` loads it),
and the design looks it up with :func:`registered_prover`. Imports nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["CASCADE_CERTIFICATE", "INPUT_BOUND", "PROVERS", "register_prover",
           "registered_prover"]

#: ``(tube, spec, *, per_axis_first=False) -> InputProof``: the peak inputs of law (13)
#: along a designed tube (:mod:`.input_bound`).
INPUT_BOUND = "input_bound"
#: ``(tube, spec, stage) -> (passed, report)``: the sampled cascade's certificate of one
#: stage; ``report`` is JSON-ready and has a ``reason`` when not passed.
CASCADE_CERTIFICATE = "cascade_certificate"
#: What the design asks a prover for.
PROVERS = (INPUT_BOUND, CASCADE_CERTIFICATE)

_REGISTERED: dict[str, Callable[..., Any]] = {}


def register_prover(kind: str, prover: Callable[..., Any]) -> None:
    """Make ``prover`` the one the design asks for ``kind`` (replacing any before).

    Parameters
    ----------
    kind : str
        One of :data:`PROVERS`.
    prover : callable
        The prover, with the signature :data:`PROVERS`'s entry documents.

    Raises
    ------
    ValueError
        ``kind`` is not one of :data:`PROVERS`.
    """
    if kind not in PROVERS:
        raise ValueError(f"unknown prover kind {kind!r}; known: {', '.join(PROVERS)}")
    _REGISTERED[kind] = prover


def registered_prover(kind: str) -> Callable[..., Any] | None:
    """The prover registered for ``kind``, or None (``stt_codegen.verify`` not loaded).

    Parameters
    ----------
    kind : str
        One of :data:`PROVERS`.

    Returns
    -------
    callable or None
        The prover last registered by :func:`register_prover`.
    """
    return _REGISTERED.get(kind)
