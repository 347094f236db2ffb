"""The registry of the sampled cascade's certifier, which the design asks for.

The certificate (:mod:`stt_codegen.verify.cascade_sampled`) builds on the design and so
cannot be imported by it; :mod:`stt_codegen.verify` registers it with
:func:`register_cascade_certifier` when the package is loaded (``import stt_codegen``
loads it), as it registers the input prover (:mod:`.input_bound`). Imports nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

#: ``certifier(tube, spec, stage) -> (passed, report)``; ``report`` is JSON-ready and has a
#: ``reason`` when not passed.
CascadeCertifier = Callable[[Any, Any, Any], "tuple[bool, dict]"]

__all__ = ["CascadeCertifier", "cascade_certifier", "register_cascade_certifier"]

_CERTIFIER: list[CascadeCertifier] = []


def register_cascade_certifier(certifier: CascadeCertifier) -> None:
    """Register the sampled cascade's certifier (the verify package does, once).

    Parameters
    ----------
    certifier : callable
        ``certifier(tube, spec, stage) -> (passed, report)``.
    """
    _CERTIFIER[:] = [certifier]


def cascade_certifier() -> CascadeCertifier:
    """The registered certifier.

    Returns
    -------
    CascadeCertifier
        ``certifier(tube, spec, stage) -> (passed, report)``.

    Raises
    ------
    RuntimeError
        None registered (``stt_codegen.verify`` not imported).
    """
    if not _CERTIFIER:
        raise RuntimeError("no cascade certifier registered: import stt_codegen first")
    return _CERTIFIER[0]
