"""SymPy proofs of the paper's formulas on the deployed expressions.

Every proof returns a :class:`Check`. They are proved on the deployed expressions: the
pieces of :mod:`stt_codegen.tube.pieces` printed by the emitter's SymPy printer. The
command that runs them on a design is :mod:`stt_codegen.verification` (the front door's
``stt_codegen.verify``). The modules:

* :mod:`.check` -- the result objects: one :class:`Check`, and a
  :class:`VerificationReport`;
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
* :mod:`.cascade` -- the second-order cascade's second stage;
* :mod:`.look_ahead` -- the differential drive's look-ahead point and base command;
* :mod:`.design_independent` -- the design-independent proofs, cached on disk.
"""

import importlib
from typing import Any

#: Public name -> submodule that defines it; imported on first use (PEP 562), so importing
#: this package costs nothing.
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
