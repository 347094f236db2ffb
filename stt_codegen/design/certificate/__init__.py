"""Continuous-time safety certificate of a designed tube, for every ``t >= 0``.

The controller keeps ``x(t)`` strictly inside the box ``[gamma_L(t), gamma_U(t)]``
(Theorem 4.1), so if that box is non-empty, misses every obstacle, stays in the state
space and, from ``t_c`` on, lies in the target, then Definition 2.1 holds whatever the
dynamics (docs/decisions.md, decision 11). This package proves those properties for the
tube the deployed controller enforces: ``alpha`` follows the controller's own
backward-Euler step of (11) at its sampling rate (linearly interpolated between the
instants), from ``alpha(0) = 0``. It also bounds how far a tube bound moves in one sampling period
(a sampled controller cannot follow a faster tube). Proofs in ``docs/design.md``.

Modules, one layer each:

* :mod:`.enclosures`: interval ranges of the tube's pieces (``rho``, the bumps, ``beta``,
  ``psi``) and their composition into an :class:`Enclosure`;
* :mod:`.implicit_step`: rigorous brackets of the implicit step of eq. (11) and of its
  fixed point, and the ranges of the deployed ``alpha`` they give;
* :mod:`.refine`: the refinement loop (:func:`certify_tube`);
* :mod:`.report`: the result types and the report of every property's margin.

The public names are importable from here. The certificates of the sampled closed loop,
which the design asks before it accepts a tube, are imported from their modules:

* :mod:`.sampled`: every plant of the class stays in the tube under the sampled law (13)
  (per-axis boxes, :mod:`.sampled_axis`, cut by Lyapunov balls, :mod:`.lyapunov`; the
  plant's bounds on each sampling interval, :mod:`.plant_class`);
* :mod:`.actuator`: the proved peak of each input of law (13) (``[actuator]``);
* :mod:`.cascade_sampled`: the sampled cascade of a second-order plant, and
  :mod:`.cascade_adversary`, members of its class that the greedy strategies drive out.
"""

from .enclosures import (Pieces, bump_ranges, circumvent_range, enclose, enclose_tube,
                         piece_ranges, reach_range, width_lower_bound)
from .implicit_step import (EXACT_STEPS, STEP_ROOT_TOLERANCE, Propagation, SequenceBounds,
                            alpha_fixed_point, alpha_ranges, sequence_bounds, step_root)
from .narrowest import (WIDTH_PIECE_BUDGET, WIDTH_SPLIT, WIDTH_TOLERANCE, Narrowest,
                        sharpen_narrowest)
from .refine import MAX_INTERVALS, MIN_INTERVAL, SPLIT, WIDTH_REFINE_ROUNDS, certify_tube
from .repropagate import repropagate, step_psi
from .report import (MAX_MOVE_PER_SAMPLE, PROPERTIES, ROUNDING_MARGIN, Certificate,
                     CertificateState, Enclosure, Margin, certificate_report,
                     obstacle_separation)

__all__ = ["EXACT_STEPS", "MAX_INTERVALS", "MAX_MOVE_PER_SAMPLE", "MIN_INTERVAL", "PROPERTIES",
           "ROUNDING_MARGIN", "SPLIT", "STEP_ROOT_TOLERANCE", "WIDTH_PIECE_BUDGET",
           "WIDTH_REFINE_ROUNDS", "WIDTH_SPLIT", "WIDTH_TOLERANCE", "Certificate",
           "CertificateState", "Enclosure", "Margin", "Narrowest", "Pieces", "Propagation",
           "SequenceBounds", "alpha_fixed_point", "alpha_ranges", "bump_ranges",
           "certificate_report", "certify_tube", "circumvent_range", "enclose",
           "enclose_tube", "obstacle_separation", "piece_ranges", "reach_range",
           "repropagate", "sequence_bounds", "sharpen_narrowest", "step_psi", "step_root",
           "width_lower_bound"]
