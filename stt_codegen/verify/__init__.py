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
* :mod:`.proofs` -- the design-independent proofs, cached on disk;
* :mod:`.command` -- every check of one design, :func:`~.command.verify`.
"""

from .adaptive import (adaptive_law_checks, adversarial_psi_signals, alpha_rate_bound,
                       alpha_upper_bound, check_adaptive_law_numeric, simulate_alpha)
from .assumption import (assumption2_omnidirectional, assumption2_single_integrator,
                         check_assumption2, symmetric_part)
from .check import Check, VerificationReport, all_passed, format_report
from .lemma import (bump_rate_bound, check_bump_flat_all_orders, check_bump_flatness,
                    check_reach_continuity, check_reach_flat_all_orders, check_smooth_max,
                    lemma_checks, reach_rate_bound, reach_rate_constant)
from .transform import (check_epsilon_jacobian, check_lyapunov_derivative,
                        error_transform_checks, outer_product_difference, xi_diagonal,
                        xi_outer_product)

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
