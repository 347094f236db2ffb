"""``stt-codegen verify``: every check of a spec's designed tube, with its evidence.

Connects the symbolic checks of this package to a concrete design: the rate bounds of
Lemma 3.3 for its tube and bumps, Assumption 2 for its plant, the adaptive-law bounds for
its ``psi``, and the continuous-time tube certificate (:mod:`stt_codegen.design.certificate`).
"""

from __future__ import annotations

import argparse
import functools
import json

import numpy as np

from ..tube import reference
from ..design.certificate import Certificate
from ..design.samples import sample_tube
from ..design.search import MAX_INITIAL_ERROR, MAX_MOVE_PER_SAMPLE, check_tube, design_tube
from ..errors import DesignError, SpecError
from ..spec.loader import Spec, load_spec
from ..spec.plants import PLANT_MODELS, dimension_mismatch
from ..tube.parameters import SMOOTHSTEP, TANH, TubeDesign
from .adaptive import adaptive_law_checks, alpha_upper_bound
from .assumption import assumption2_omnidirectional, assumption2_single_integrator
from .check import Check, VerificationReport
from .deployed import deployed_checks
from .lemma import bump_rate_bound, lemma_checks, reach_rate_bound
from .sampled import linear_plant_checks, sampled_checks
from .transform import error_transform_checks

#: Dimension names used in check names.
_SIDES = ("L", "U")


@functools.lru_cache(maxsize=None)
def symbolic_checks(max_n: int) -> tuple[Check, ...]:
    """The design-independent proofs: the deployed pieces equal the paper's formulas
    (``deployed.*``), Lemma 3.3 limits, smooth max, error transform.

    They take SymPy some seconds and depend on no parameter, so a process proves them once.
    """
    return (tuple(deployed_checks()) + tuple(lemma_checks(orders=3))
            + tuple(error_transform_checks(max_n=max_n)))


def _psi_ranges(design: TubeDesign, certificate: Certificate) -> tuple[np.ndarray, np.ndarray]:
    """Certified ``min_t psi`` (over every ``t >= 0``) and ``psi(0)``, shape (2n,) each."""
    psi_min = certificate.enclosure.psi_min.min(axis=0)
    psi0 = reference.conflict_distance(design, 0.0)[0]
    return psi_min, psi0


def verify_design(spec: Spec, design: TubeDesign, plant: str | None = None) -> list[Check]:
    """Run every check on a designed tube.

    Parameters
    ----------
    spec : Spec
    design : TubeDesign
    plant : str, optional
        Plant model for Assumption 2 (one of :data:`stt_codegen.spec.plants.PLANT_MODELS`);
        default the spec's.

    Returns
    -------
    list of Check
        In order: Lemma 3.3, the error transform, the equality of each deployed piece with
        the paper's formula (``deployed.*``), Assumption 2 (and, for the linear
        plant, whether it meets ``[assumptions]``), the adaptive law (per component of
        ``alpha``), the tube certificate, and the sampled closed loop
        (:func:`~stt_codegen.verify.sampled.sampled_checks`).
    """
    model = plant or spec.plant_model
    tube_check = check_tube(design, spec)
    enclosure = tube_check.certificate.enclosure
    n = design.dimension
    reach = sorted({(a, b, seg.duration) for seg in design.segments if seg.profile == TANH
                    for a, b in zip(seg.lower_from + seg.upper_from,
                                    seg.lower_to + seg.upper_to) if a != b})
    bumps = [(c.sharpness, c.radius, c.height) for c in design.circumvents]
    symbolic = symbolic_checks(min(n, 3))
    reach_checks = [reach_rate_bound(*p) for p in reach]
    bump_checks = [bump_rate_bound(*p) for p in bumps]
    checks = [c for c in symbolic if c.name.startswith("lemma")] + reach_checks + bump_checks
    checks += [c for c in symbolic if not c.name.startswith(("lemma", "deployed"))]
    checks += [c for c in symbolic if c.name.startswith("deployed")]
    # smooth-step segments: sup |d/dt tau^3 (10 - 15 tau + 6 tau^2)| = 30/16 per duration
    # (at tau = 1/2, where 30 tau^2 (1 - tau)^2 is largest)
    smooth_rates = [abs(b - a) * 1.875 / seg.duration for seg in design.segments
                    if seg.profile == SMOOTHSTEP
                    for a, b in zip(seg.lower_from + seg.upper_from, seg.lower_to + seg.upper_to)]
    rho_rate = max([c.data.get("bound", 0.0) for c in reach_checks] + smooth_rates,
                   default=0.0)
    bump_rate = {p: chk.data.get("bound", np.inf) for p, chk in zip(bumps, bump_checks)}

    if model == "omnidirectional":
        checks.append(assumption2_omnidirectional((spec.state_space.lower[2],
                                                   spec.state_space.upper[2])))
    elif model == "linear":
        checks += linear_plant_checks(spec)
    else:
        checks.append(assumption2_single_integrator(n))

    psi_min, psi0 = _psi_ranges(design, tube_check.certificate)
    for c in range(2 * n):
        i, side = c % n, _SIDES[c // n]
        other = "upper" if side == "L" else "lower"
        beta_rate = sum(bump_rate[(b.sharpness, b.radius, b.height)]
                        for b in design.circumvents_on(i, other))
        label = f"x{i + 1},{side}"
        for check in adaptive_law_checks(float(psi_min[c]), design.theta0, design.kappa,
                                         design.mu, float(psi0[c]), rho_rate + beta_rate):
            if check.name in ("adaptive.parameters", "adaptive.nonnegative"):
                if c == 0:      # independent of psi: report once
                    checks.append(check)
                continue
            checks.append(Check(f"{check.name}[{label}]", check.passed, check.detail,
                                check.data))
        a_max = alpha_upper_bound(float(psi_min[c]), design.theta0, design.kappa, design.mu)
        peak = float(enclosure.alpha_max[:, c].max())
        lowest = float(enclosure.alpha_min[:, c].min())
        # both sides are the same fixed point where psi is constant, each bracketed
        # outward to ~1e-11: compare within that rounding
        within = peak <= a_max * (1.0 + 1e-10) + 1e-15
        checks.append(Check(f"adaptive.deployed[{label}]", bool(0 <= lowest and within),
                            f"the deployed alpha stays in [0, {peak:.6g}] (certified, every "
                            f"t >= 0) within the bound "
                            f"{a_max:.6g}", {"peak": peak, "alpha_max": a_max}))

    checks.append(Check("tube.sampling_rate", tube_check.max_move_ratio <= MAX_MOVE_PER_SAMPLE,
                        f"a tube bound moves at most {tube_check.max_move_ratio:.3g} tube widths in "
                        f"one sampling period at {design.rate_hz:g} Hz (limit "
                        f"{MAX_MOVE_PER_SAMPLE}: a sampled controller cannot follow faster)",
                        {"max_move_ratio": tube_check.max_move_ratio}))
    checks.append(Check("tube.initial_room", tube_check.initial_error <= MAX_INITIAL_ERROR,
                        f"x(0) starts at |e| = {tube_check.initial_error:.3g} of the tube's "
                        f"half-width at t = 0 (limit {MAX_INITIAL_ERROR}: closer to the edge "
                        "the first sampled steps overshoot)",
                        {"initial_error": tube_check.initial_error}))
    for margin in tube_check.certificate.margins:
        if margin.name == "sampling rate":   # reported above as tube.sampling_rate
            continue
        checks.append(Check(f"tube.{margin.name.replace(' ', '_')}", margin.passed,
                            margin.detail, {"margin": margin.margin, "time": margin.time}))
    # the sampled loop is followed sample by sample (sample_tube refuses a horizon over its
    # step budget with a SpecError)
    checks += sampled_checks(spec, design, sample_tube(design), tube_check.certificate)
    return checks


def verify_spec(spec: Spec, plant: str | None = None) -> list[Check]:
    """Design the tube of a spec and run :func:`verify_design`; a design failure is a FAIL."""
    try:
        design = design_tube(spec).tube
    except DesignError as exc:
        return [Check("tube.design", False, str(exc))]
    return verify_design(spec, design, plant)


def verify(spec: Spec, design: TubeDesign | None = None,
           plant: str | None = None) -> VerificationReport:
    """Check the paper's lemmas, the assumptions and the tube certificate for a spec.

    The checks run on the deployed expressions (the pieces of :mod:`stt_codegen.tube.pieces`
    printed by the SymPy printer; ``deployed.*`` proves each equal to the paper's formula
    where the code writes it differently): Lemma 3.3 (smoothness of eqs. (4), (7)-(10)
    and explicit rate bounds),
    the error transform and the Lyapunov derivative of Theorem 4.1 (eq. (12), law (13)),
    Assumption 2 for the plant, the adaptive law (11) per component of ``alpha``, the
    sampling-rate limit, the room at the start and the continuous-time certificate of the
    tube (non-empty, contains ``x(0)``, in the state space, misses every obstacle, in the
    target from ``t_c`` on).

    Parameters
    ----------
    spec : Spec
        From :func:`stt_codegen.load_spec` or :meth:`stt_codegen.Spec.from_dict`.
    design : TubeDesign, optional
        The design to check; by default the tube is designed first, and a spec with no
        design gives a report whose one check, ``tube.design``, failed.
    plant : str, optional
        Plant model for Assumption 2 (``"omnidirectional"`` or ``"single-integrator"``);
        default the spec's ``plant.model``.

    Returns
    -------
    VerificationReport
        ``report.passed`` is ``True`` when every check passed; ``report.failed`` lists
        the others with their evidence.

    Raises
    ------
    SpecError
        Unknown plant model (field ``plant``), or one that does not fit the spec's
        dimension.
    """
    if plant is not None and plant not in PLANT_MODELS:
        raise SpecError("plant", f"must be one of {', '.join(PLANT_MODELS)}")
    if plant is not None and dimension_mismatch(plant, spec.dimension):
        raise SpecError("plant", dimension_mismatch(plant, spec.dimension))
    checks = verify_spec(spec, plant) if design is None else verify_design(spec, design, plant)
    return VerificationReport(spec.name, tuple(checks))


def _cmd_verify(args: argparse.Namespace) -> int:
    report = verify(load_spec(args.spec), plant=args.plant)
    print(json.dumps(report.to_json(), indent=2) if args.json else str(report))
    return 0 if report.passed else 1


def configure_verify(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen verify``."""
    p.add_argument("spec", metavar="SPEC", help="bundled case name or spec file")
    p.add_argument("--json", action="store_true", help="print a JSON list of checks")
    p.add_argument("--plant", default=None, metavar="MODEL",
                   help=f"plant for Assumption 2 ({', '.join(PLANT_MODELS)}; default: the spec's)")
    p.set_defaults(handler=_cmd_verify)
