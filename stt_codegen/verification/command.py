"""Every check of a spec's designed tube, with its evidence (``stt-codegen verify``).

Connects the symbolic checks of this package to a concrete design: the rate bounds of
Lemma 3.3 for its tube and bumps, Assumption 2 for its plant, the adaptive-law bounds for
its ``psi``, and the continuous-time tube certificate (:mod:`stt_codegen.design.certificate`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..tube import reference
from ..design.certificate import Certificate
from ..design.certificate.actuator import prove_input_bound
from ..design.result import Design
from ..design.search import MAX_INITIAL_ERROR, MAX_MOVE_PER_SAMPLE, check_tube, design_tube
from ..errors import DesignError, SpecError
from ..spec.loader import Spec
from ..spec.variants import variant_of
from ..spec.plants import MODELS_WITH_EQUATIONS
from ..tube.parameters import TANH, TubeDesign, peak_rate_factor
from ..proofs.adaptive import adaptive_law_checks, alpha_upper_bound
from ..proofs.assumption import assumption2_check
from ..proofs.look_ahead import look_ahead_inverse
from ..design.look_ahead import base_proof
from ..rounding import distinct
from ..proofs.check import Check, VerificationReport
from ..progress import ProgressCallback, Reporter
from ..proofs.lemma import bump_rate_bound, reach_rate_bound
from ..proofs.design_independent import design_independent_proofs
from .sampled import delay_check, input_bound_check, plant_bounds_checks, sampled_checks

__all__ = ["cascade_sampled_checks", "first_order_model_checks", "first_order_sampled_checks",
           "look_ahead_model_checks", "look_ahead_sampled_checks", "no_model_checks",
           "spec_for_plant", "verify", "verify_design", "verify_spec"]

#: Dimension names used in check names.
_SIDES = ("L", "U")

#: The stages ``verify`` reports to its ``progress`` callback, in order; the proofs from
#: the cache are reported as the last proof stage.
STAGES = ("design", "deployed pieces", "lemma 3.3", "error transform", "rate bound forms",
          "rate bounds", "assumption 2", "tube certificate", "adaptive law", "sampled loop")
_CACHED = "cached proofs"


class _Stages:
    """``progress`` wrapped to report :class:`~stt_codegen.progress.Progress` events for
    the stages of one run: stage ``i`` of ``N`` at fraction ``(i - 1) / N``, message
    ``"<stage> (i/N)"``; :meth:`finish` reports ``("done", 1.0)``."""

    def __init__(self, progress: ProgressCallback | None, design: bool) -> None:
        self.reporter = Reporter(progress)
        self.names = STAGES if design else STAGES[1:]

    def __call__(self, label: str) -> None:
        index = self.names.index("rate bound forms" if label == _CACHED else label) + 1
        self.reporter(label, (index - 1) / len(self.names),
                      f"{label} ({index}/{len(self.names)})")

    def finish(self) -> None:
        """The last event: every stage done."""
        self.reporter("done", 1.0, f"done ({len(self.names)}/{len(self.names)})")


def _psi_ranges(design: TubeDesign, certificate: Certificate) -> tuple[np.ndarray, np.ndarray]:
    """Certified ``min_t psi`` (over every ``t >= 0``) and ``psi(0)``, shape (2n,) each."""
    psi_min = certificate.enclosure.psi_min.min(axis=0)
    psi0 = reference.conflict_distance(design, 0.0)[0]
    return psi_min, psi0


def _deployed_alpha_check(label: str, alpha_max: float, peak: float, lowest: float) -> Check:
    """``adaptive.deployed``: the deployed ``alpha`` stays in ``[0, alpha_max]``.

    The certificate's enclosure of the deployed ``alpha`` (``[lowest, peak]``) proves it
    when ``0 <= lowest`` and ``peak <= alpha_max``. Where ``psi`` sits at its minimum for
    long, both sides are the same fixed point and the enclosure's outward brackets (about
    ``1e-10`` relative after many intervals) may end a hair above ``alpha_max``; the
    bound then follows by induction over the samples instead: the implicit step's root
    increases with ``alpha_k`` and ``theta`` and decreases with ``psi``; with ``alpha_k <=
    alpha_max``, ``psi >= psi_min`` (certified) and ``theta <= theta_sup`` it is at most the
    root at (``alpha_max``, ``psi_min``, ``theta_sup``), which is ``alpha_max`` itself
    (``kappa a (psi_min + a)^2 = theta_sup`` is the step's fixed point, and
    :func:`~stt_codegen.proofs.adaptive.alpha_upper_bound` returns a double with
    ``f(alpha_max) >= theta_sup`` exactly); ``alpha_0 = 0``. Either way the figures are
    printed to ten digits, so a reader sees what was compared.
    """
    enclosed = peak <= alpha_max
    how = ("the certificate's enclosure of it peaks there" if enclosed else
           f"by induction over the samples (monotone implicit step with fixed point alpha_max;"
           f" the certificate's enclosure peaks {(peak - alpha_max) / alpha_max:.2g} relative"
           " above it, its brackets' rounding)")
    return Check(f"adaptive.deployed[{label}]", bool(0.0 <= lowest),
                 f"the deployed alpha stays in [{max(lowest, 0.0):.10g}, {alpha_max:.10g}] "
                 f"(every t >= 0; enclosure low end {lowest:.10g}, peak {peak:.10g}): {how}",
                 {"peak": peak, "lowest": lowest, "alpha_max": alpha_max,
                  "proved_by": "enclosure" if enclosed else "induction"})


def verify_design(spec: Spec, design: TubeDesign, plant: str | None = None, *,
                  cache: bool = True,
                  progress: ProgressCallback | None = None) -> list[Check]:
    """Run every check on a designed tube.

    Parameters
    ----------
    spec : Spec
        The spec the tube was designed for.
    design : TubeDesign
        Its designed tube and gain.
    plant : str, optional
        Plant model (one of :data:`stt_codegen.spec.plants.MODELS_WITH_EQUATIONS`) for Assumption 2
        and the sampled check's bounds (:meth:`~stt_codegen.spec.loader.Spec.with_plant_model`);
        default the spec's.
    cache : bool
        Take the design-independent proofs from the proof cache
        (:func:`~stt_codegen.proofs.design_independent.design_independent_proofs`).
    progress : callable, optional
        Called with a :class:`~stt_codegen.progress.Progress` before each stage (message
        ``"<stage> (i/N)"``), as :func:`verify`.

    Returns
    -------
    list of Check
        In order: Lemma 3.3, the error transform, the equality of each deployed piece with
        the paper's formula (``deployed.*``), Assumption 2 (and, for the linear
        plant, whether it meets ``[assumptions]``), the adaptive law (per component of
        ``alpha``), the tube certificate, the sampled closed loop
        (:func:`~stt_codegen.verification.sampled.sampled_checks`) and, for a spec with
        ``[actuator]``, ``sampled.input_bound``
        (:func:`~stt_codegen.verification.sampled.input_bound_check`). For a spec with
        a second-order ``plant.model``, the cascade's lemmas (:func:`~stt_codegen.proofs.cascade.cascade_checks`),
        and the sampled cascade's certificate ``cascade.sampled``
        (:func:`~stt_codegen.verification.cascade.sampled_cascade_check`) instead of the last
        two, with ``[actuator]`` followed by ``cascade.input_bound``
        (:func:`~stt_codegen.verification.cascade.cascade_input_bound_check`).
    """
    stage = progress if isinstance(progress, _Stages) else _Stages(progress, design=False)
    if plant is not None:
        spec = spec.with_plant_model(plant)      # the plant's own bounds (SpecError if the
    model = spec.plant_model                     # declared [assumptions] contradict them)
    n = design.dimension
    proofs = design_independent_proofs(min(n, 3), cache=cache, progress=stage)
    reach = sorted({(a, b, seg.duration) for seg in design.segments if seg.profile == TANH
                    for a, b in zip(seg.lower_from + seg.upper_from,
                                    seg.lower_to + seg.upper_to) if a != b})
    bumps = [(c.sharpness, c.radius, c.height) for c in design.circumvents]
    symbolic = proofs.checks
    stage("rate bounds")
    reach_checks = [reach_rate_bound(*p, form=proofs.forms["reach_rate"]) for p in reach]
    bump_checks = [bump_rate_bound(*p, form=proofs.forms["bump_rate"]) for p in bumps]
    checks = [c for c in symbolic if c.name.startswith("lemma")] + reach_checks + bump_checks
    checks += [c for c in symbolic if not c.name.startswith(("lemma", "deployed"))]
    checks += [c for c in symbolic if c.name.startswith("deployed")]
    # smooth segments (smooth step, cruise): sup |rho_dot| = |to - from| times the
    # profile's peak of dp/dtau per duration; at a blended corner two segments move the
    # tube at once, so their sups add
    tanh_rate = max([c.data.get("bound", 0.0) for c in reach_checks], default=0.0)
    segment_rates = [max((abs(b - a) * peak_rate_factor(seg.profile) / seg.duration
                          for a, b in zip(seg.lower_from + seg.upper_from,
                                          seg.lower_to + seg.upper_to)), default=0.0)
                     if seg.profile != TANH else tanh_rate for seg in design.segments]
    blended = [segment_rates[k] + segment_rates[k + 1]
               for k, (a, b) in enumerate(zip(design.segments, design.segments[1:]))
               if b.start < a.end]
    rho_rate = max([tanh_rate] + segment_rates + blended)
    bump_rate = {p: chk.data.get("bound", np.inf) for p, chk in zip(bumps, bump_checks)}

    stage("assumption 2")
    checks.append(assumption2_check(spec, model))
    variant = variant_of(spec)
    checks += variant.entry("model_checks")(spec, model)

    stage("tube certificate")
    tube_check = check_tube(design, spec)   # not the designer's: verify certifies again
    enclosure = tube_check.certificate.enclosure
    stage("adaptive law")
    psi_min, psi0 = _psi_ranges(design, tube_check.certificate)
    for c in range(2 * n):
        i, side = c % n, _SIDES[c // n]
        other = "upper" if side == "L" else "lower"
        beta_rate = sum(bump_rate[(b.sharpness, b.radius, b.height)]
                        for b in design.circumvents_on(i, other))
        label = f"x{i + 1},{side}"
        for check in adaptive_law_checks(float(psi_min[c]), design.theta0, design.kappa,
                                         design.mu, float(psi0[c]), rho_rate + beta_rate,
                                         form=proofs.forms["adaptive_law"]):
            if check.name in ("adaptive.parameters", "adaptive.nonnegative"):
                if c == 0:      # independent of psi: report once
                    checks.append(check)
                continue
            checks.append(Check(f"{check.name}[{label}]", check.passed, check.detail,
                                check.data))
        checks.append(_deployed_alpha_check(
            label, alpha_upper_bound(float(psi_min[c]), design.theta0, design.kappa,
                                     design.mu),
            float(enclosure.alpha_max[:, c].max()), float(enclosure.alpha_min[:, c].min())))

    checks.append(Check("tube.sampling_rate", tube_check.max_move_ratio <= MAX_MOVE_PER_SAMPLE,
                        f"a tube bound moves at most "
                        f"{distinct(tube_check.max_move_ratio, MAX_MOVE_PER_SAMPLE)} tube widths in "
                        f"one sampling period at {design.rate_hz:g} Hz (limit "
                        f"{MAX_MOVE_PER_SAMPLE}: a sampled controller cannot follow faster)",
                        {"max_move_ratio": tube_check.max_move_ratio}))
    checks.append(Check("tube.initial_room", tube_check.initial_error <= MAX_INITIAL_ERROR,
                        f"x(0) starts at |e| = "
                        f"{distinct(tube_check.initial_error, MAX_INITIAL_ERROR)} of the tube's "
                        f"half-width at t = 0 (limit {MAX_INITIAL_ERROR}: closer to the edge "
                        "the first sampled steps overshoot)",
                        {"initial_error": tube_check.initial_error}))
    for margin in tube_check.certificate.margins:
        if margin.name == "sampling rate":   # reported above as tube.sampling_rate
            continue
        checks.append(Check(f"tube.{margin.name.replace(' ', '_')}", margin.passed,
                            margin.detail, {"margin": margin.margin, "time": margin.time}))
    # the variant's sampled loop (law (13)'s, or the cascade's certificate and lemmas)
    checks += variant.entry("sampled_checks")(spec, design, tube_check, stage)
    return checks


def first_order_model_checks(spec: Spec, model: str) -> list[Check]:
    """The checks of law (13)'s plant model (role ``model_checks`` of
    :mod:`~stt_codegen.spec.variants`): whether it meets ``[assumptions]``
    (:func:`~stt_codegen.verify.sampled.plant_bounds_checks`).

    Parameters
    ----------
    spec : Spec
    model : str
        The plant model judged.

    Returns
    -------
    list of Check
    """
    return plant_bounds_checks(spec, model)


def look_ahead_model_checks(spec: Spec, model: str) -> list[Check]:
    """The checks of a differential-drive base's model (role ``model_checks``): the
    deployed command inverts the base's kinematics, then law (13)'s.

    Parameters
    ----------
    spec : Spec
    model : str
        The plant model judged.

    Returns
    -------
    list of Check
    """
    return [look_ahead_inverse()] + plant_bounds_checks(spec, model)


def no_model_checks(spec: Spec, model: str) -> list[Check]:
    """The cascade's model checks here (role ``model_checks``): none, its membership
    check is reported with its lemmas (:func:`cascade_sampled_checks`).

    Parameters
    ----------
    spec : Spec
    model : str

    Returns
    -------
    list of Check
        Empty.
    """
    return []


def _law13_sampled(spec: Spec, design: TubeDesign, tube_check, progress,
                   input_proof: Callable) -> list[Check]:
    """The sampled loop of law (13) and, with ``[actuator]``, the input bound, the proof
    of law (13)'s peaks mapped by ``input_proof(proof, spec)`` to the variant's input."""
    progress("sampled loop")
    # the sampled loop is followed sample by sample (sample_tube refuses a horizon over its
    # step budget with a SpecError); the oracle's exp/log/tanh as numpy's ufuncs (within an
    # ulp of libm, tens of times faster), as the certificate and the input-bound prover
    # do: every margin here is far above rounding
    with reference.numpy_math():
        checks = sampled_checks(spec, design, tube_check.certificate)
        checks += [c for c in (delay_check(spec, design),) if c is not None]
    if spec.input_bound is not None:
        checks.append(input_bound_check(spec, input_proof(prove_input_bound(design, spec),
                                                          spec)))
    return checks


def first_order_sampled_checks(spec: Spec, design: TubeDesign, tube_check,
                               progress: Callable[[str], None]) -> list[Check]:
    """The sampled closed loop of law (13) and, with ``[actuator]``, ``sampled.input_bound``
    (role ``sampled_checks``).

    Parameters
    ----------
    spec : Spec
    design : TubeDesign
    tube_check : TubeCheck
        ``verify``'s own check of the tube.
    progress : callable
        Called with the stage's name.

    Returns
    -------
    list of Check
    """
    return _law13_sampled(spec, design, tube_check, progress, lambda proof, _spec: proof)


def look_ahead_sampled_checks(spec: Spec, design: TubeDesign, tube_check,
                              progress: Callable[[str], None]) -> list[Check]:
    """The sampled closed loop of law (13) on the look-ahead point and, with
    ``[actuator]``, the bound of ``(v, omega)`` of the base from the point's peaks (role
    ``sampled_checks``).

    Parameters
    ----------
    spec : Spec
    design : TubeDesign
    tube_check : TubeCheck
    progress : callable

    Returns
    -------
    list of Check
    """
    return _law13_sampled(spec, design, tube_check, progress, lambda proof, base:
                          base_proof(proof, design, base))


def cascade_sampled_checks(spec: Spec, design: TubeDesign, tube_check,
                           progress: Callable[[str], None]) -> list[Check]:
    """The deployed controller is the cascade, not law (13) on this plant: its lemmas,
    its plant's membership in its class and its sampled-data certificate, with
    ``[actuator]`` the bound of the physical input (role ``sampled_checks``;
    docs/second-order.md).

    Parameters
    ----------
    spec : Spec
    design : TubeDesign
    tube_check : TubeCheck
    progress : callable

    Returns
    -------
    list of Check
    """
    from ..proofs.cascade import cascade_checks
    from .cascade import (cascade_delay_check, cascade_input_bound_check,
                          plant_within_class_check, sampled_cascade_check)
    progress("sampled loop")          # the cascade takes the sampled loop's slot
    checks = cascade_checks(min(design.dimension, 2)) + [
        plant_within_class_check(spec),
        sampled_cascade_check(spec, design, tube_check.min_width)]
    checks += [c for c in (cascade_delay_check(spec, design, tube_check.min_width),)
               if c is not None]
    if spec.input_bound is not None:     # the physical input u: force or torque
        checks.append(cascade_input_bound_check(spec, design, tube_check.min_width))
    return checks


def spec_for_plant(spec: Spec, plant: str | None) -> Spec:
    """The spec to design for when Assumption 2 and the sampled check are judged for
    ``plant``: ``spec`` with ``plant`` as its plant model and that model's own bounds
    (:meth:`~stt_codegen.spec.loader.Spec.with_plant_model`; ``spec`` itself when
    ``plant`` is ``None``), so that the design refuses a plant that violates the
    assumption.

    Parameters
    ----------
    spec : Spec
        The spec.
    plant : str or None
        A plant model, or ``None`` for the spec's own.

    Returns
    -------
    Spec
        The spec for ``plant``.

    Raises
    ------
    SpecError
        Field ``plant``: not one of :data:`~stt_codegen.spec.plants.MODELS_WITH_EQUATIONS`, or a
        model that does not fit the spec's dimension; a declared ``[assumptions]`` bound
        that the model violates (the field names the key).
    """
    if plant is None:
        return spec
    if plant not in MODELS_WITH_EQUATIONS:
        raise SpecError("plant", f"must be one of {', '.join(MODELS_WITH_EQUATIONS)} (a model "
                                 "with equations)")
    return spec.with_plant_model(plant)


def verify_spec(spec: Spec, plant: str | None = None, *, cache: bool = True,
                progress: ProgressCallback | None = None) -> list[Check]:
    """Design the tube of a spec and run :func:`verify_design`; a design failure is a FAIL.

    With ``plant``, the tube is designed for that plant model instead of the spec's
    (:func:`spec_for_plant`).

    Parameters
    ----------
    spec : Spec
        The spec.
    plant, cache, progress
        As :func:`verify_design`.

    Returns
    -------
    list of Check
        :func:`verify_design`'s checks, or the single failed check ``tube.design`` when no
        tube can be designed.

    Raises
    ------
    SpecError
        As :func:`spec_for_plant`.
    """
    stage = progress if isinstance(progress, _Stages) else _Stages(progress, design=True)
    stage("design")
    try:
        design = design_tube(spec_for_plant(spec, plant))
    except DesignError as exc:
        return [Check("tube.design", False, str(exc))]
    return verify_design(spec, design.tube, plant, cache=cache, progress=stage)


def verify(design_or_spec: Design | Spec, *, plant: str | None = None,
           progress: ProgressCallback | None = None,
           cache: bool = True) -> VerificationReport:
    """Check the paper's lemmas, the assumptions and the tube certificate of a design.

    The checks run on the deployed expressions (the pieces of :mod:`stt_codegen.tube.pieces`
    printed by the SymPy printer; ``deployed.*`` proves each equal to the paper's formula
    where the code writes it differently): Lemma 3.3 (smoothness of eqs. (4), (7)-(10)
    and explicit rate bounds), the error transform and the Lyapunov derivative of
    Theorem 4.1 (eq. (12), law (13)), Assumption 2 for the plant, the adaptive law (11)
    per component of ``alpha``, the sampling-rate limit, the room at the start, the
    continuous-time certificate of the tube (non-empty, contains ``x(0)``, in the state
    space, misses every obstacle, in the target from ``t_c`` on) and the sampled closed
    loop for every plant of the spec's ``[assumptions]``. ``docs/verification.md`` says
    what each check proves.

    The proofs that depend on no spec parameter are taken from an on-disk cache keyed by a
    hash of everything they depend on (:mod:`stt_codegen.proofs.design_independent`), so only the
    first run on a machine pays for them.

    Parameters
    ----------
    design_or_spec : Design or Spec
        A :class:`~stt_codegen.design.result.Design` (from
        :func:`stt_codegen.design_tube`), checked against its own ``design.spec`` (its
        tube is certified again here, not taken from ``design.certificate``); or a
        :class:`~stt_codegen.spec.loader.Spec`, designed first: a spec with no design
        gives a report whose one check, ``tube.design``, failed.
    plant : str, optional
        Plant model for Assumption 2 and the sampled check's bounds (one of
        :data:`~stt_codegen.spec.plants.MODELS_WITH_EQUATIONS`;
        :meth:`~stt_codegen.spec.loader.Spec.with_plant_model`); default the spec's
        ``plant.model``.
    progress : callable, optional
        Called with a :class:`~stt_codegen.progress.Progress` before each stage: its
        ``stage`` (``"lemma 3.3"``), the ``fraction`` of the stages done and the
        ``message`` ``"<stage> (i/N)"`` (``"lemma 3.3 (3/10)"``); the last event is
        ``("done", 1.0)``. The command line draws them as a bar on a terminal; the same
        type as :func:`~stt_codegen.design_tube`'s ``progress``.
    cache : bool
        Read and write the proof cache (default); ``False`` proves everything again
        and touches no file. The report is the same either way.

    Returns
    -------
    VerificationReport
        ``report.passed`` is ``True`` when every check passed; ``report.failed`` lists
        the others with their evidence.

    Raises
    ------
    SpecError
        Unknown plant model (field ``plant``), one that does not fit the spec's
        dimension, or one that violates a declared ``[assumptions]`` bound (the field
        names the key).
    TypeError
        ``design_or_spec`` is neither a ``Design`` nor a ``Spec`` (for example a
        ``(spec, tube)`` pair: pass the ``Design``, which carries its spec).

    See Also
    --------
    stt_codegen.design_tube : the design to verify.
    stt_codegen.proofs.design_independent.design_independent_proofs : the cached proofs.
    stt_codegen.proofs.check.VerificationReport : the result.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> report = stt.verify(design)
    >>> report.passed
    True
    >>> report["lemma3.3.reach.continuity"].passed
    True
    >>> stt.verify(stt.load_spec("omnirobot-s1")).passed       # designs it first
    True
    """
    if isinstance(design_or_spec, Design):
        spec = design_or_spec.spec
    elif isinstance(design_or_spec, Spec):
        spec = design_or_spec
    else:
        raise TypeError(f"verify(): parameter 'design_or_spec' must be a Design or a Spec, not "
                        f"{type(design_or_spec).__name__}; pass the Design that "
                        "stt_codegen.design_tube(spec) returned (it carries its spec), or the "
                        "Spec")
    spec_for_plant(spec, plant)     # a bad plant is refused before any work
    stages = _Stages(progress, design=not isinstance(design_or_spec, Design))
    if isinstance(design_or_spec, Design):
        checks = verify_design(spec, design_or_spec.tube, plant, cache=cache,
                               progress=stages)
    else:
        checks = verify_spec(spec, plant, cache=cache, progress=stages)
    stages.finish()
    return VerificationReport(spec.name, tuple(checks))

