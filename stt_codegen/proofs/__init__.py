"""Symbolic and numeric verification of the paper's formulas (``stt-codegen verify``).

The entry point is the function :func:`stt_codegen.verify.command.verify` (the front
door's ``stt_codegen.verify``): ``verify(design)`` or ``verify(spec)`` returns a
:class:`VerificationReport`.

Every check returns a :class:`Check`. The checks are proved on the deployed expressions:
the pieces of :mod:`stt_codegen.tube.pieces` printed by the emitter's SymPy printer. The
modules:

* :mod:`.deployed` -- the deployed expressions as SymPy, reduced to a domain, and their
  equality with the paper's formulas (``deployed.*``);
* :mod:`.statements` -- the paper's formulas as stated, the right-hand sides of those
  equalities only;
* :mod:`.lemma` -- Lemma 3.3 pieces: smoothness of the tubes (4), (7)-(8),
  (9)-(10) and explicit rate bounds;
* :mod:`.transform` -- error transform and the Lyapunov derivative of the proof
  of Theorem 4.1;
* :mod:`.assumption` -- Assumption 2 for a plant's input matrix (the named plants' from
  :mod:`stt_codegen.runtime.dynamics`);
* :mod:`.adaptive` -- non-negativity and an explicit bound of the adaptive law (11);
* :mod:`.sampled` -- the sampled closed loop for every plant of ``[assumptions]``;
* :mod:`.actuator` -- the input bound of ``[actuator]`` from the sampled check's bound on
  ``e`` (``sampled.input_bound``; registered as the design's input prover);
* :mod:`.proofs` -- the design-independent proofs, cached on disk;
* :mod:`.command` -- every check of one design, :func:`~.command.verify`.
"""

import importlib
from typing import Any

from ..design.provers import CASCADE_CERTIFICATE, INPUT_BOUND, register_prover

#: Public name -> submodule that defines it; imported on first use (PEP 562), so importing
#: this package costs nothing (``import stt_codegen`` imports it, see there).
_LAZY: dict[str, str] = {
    **dict.fromkeys(("adaptive_law_checks", "adversarial_psi_signals", "alpha_rate_bound",
                     "alpha_upper_bound", "check_adaptive_law_numeric", "simulate_alpha"),
                    "adaptive"),
    **dict.fromkeys(("assumption2_omnidirectional", "assumption2_single_integrator",
                     "check_assumption2", "symmetric_part"), "assumption"),
    **dict.fromkeys(("Check", "VerificationReport", "all_passed", "format_report"), "check"),
    **dict.fromkeys(("bump_rate_bound", "check_bump_flat_all_orders", "check_bump_flatness",
                     "check_reach_continuity", "check_reach_flat_all_orders",
                     "check_smooth_max", "lemma_checks", "reach_rate_bound",
                     "reach_rate_constant"), "lemma"),
    **dict.fromkeys(("check_epsilon_jacobian", "check_lyapunov_derivative",
                     "error_transform_checks", "outer_product_difference", "xi_diagonal",
                     "xi_outer_product"), "transform"),
}


def _prove_input_bound(tube: Any, spec: Any, *, per_axis_first: bool = False) -> Any:
    """:func:`.actuator.prove_input_bound`, imported on first use."""
    from .actuator import prove_input_bound
    return prove_input_bound(tube, spec, per_axis_first=per_axis_first)


# The design accepts a tube under [actuator] only with this proof (the sampled-data
# check's bound on e, verify's), and cannot import verify, which builds on it: the
# prover is registered here, when the package is loaded (``import stt_codegen`` loads it).
register_prover(INPUT_BOUND, _prove_input_bound)


def _certify_cascade(tube: Any, spec: Any, stage: Any) -> tuple[bool, dict]:
    """:func:`.cascade_sampled.certify_stage`, imported on first use."""
    from .cascade_sampled import certify_stage
    return certify_stage(tube, spec, stage)


# The design keeps a second stage only when the sampled cascade is certified (verify's
# certificate, registered here for the same reason as the input prover).
register_prover(CASCADE_CERTIFICATE, _certify_cascade)


def __getattr__(name: str) -> Any:
    """Import a public name on first use (PEP 562)."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "Check",
    "VerificationReport",
    "all_passed",
    "format_report",
    # Lemma 3.3
    "bump_rate_bound",
    "check_bump_flat_all_orders",
    "check_bump_flatness",
    "check_reach_continuity",
    "check_reach_flat_all_orders",
    "check_smooth_max",
    "lemma_checks",
    "reach_rate_bound",
    "reach_rate_constant",
    # error transform, Theorem 4.1
    "check_epsilon_jacobian",
    "check_lyapunov_derivative",
    "error_transform_checks",
    "outer_product_difference",
    "xi_diagonal",
    "xi_outer_product",
    # Assumption 2
    "assumption2_omnidirectional",
    "assumption2_single_integrator",
    "check_assumption2",
    "symmetric_part",
    # adaptive law (11)
    "adaptive_law_checks",
    "adversarial_psi_signals",
    "alpha_rate_bound",
    "alpha_upper_bound",
    "check_adaptive_law_numeric",
    "simulate_alpha",
]
