"""The result of a tube design: the tube, how it was found, its check and certificate, its cost."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from ..display import Rows, markdown, text
from ..spec.variants import require_variant, variant_of
from ..errors import SpecError
from ..spec.robot import robot_json
from ..tube.look_ahead import LookAhead
from ..tube.parameters import TubeDesign
from ..tube.second_stage import SecondStage
from .cascade_gain import second_stage_for
from .certificate import Certificate
from .failures import FailureKind
from .input_bound import InputProof
from .samples import sample_tube

if TYPE_CHECKING:
    from ..spec.loader import Spec
    from .tasks import TaskPlan

__all__ = ["Design", "METHOD_PAPER", "METHOD_VIA", "TubeCheck", "cascade_stage",
           "cascade_stage_json", "cascade_summary_rows", "look_ahead_stage",
           "look_ahead_summary_rows", "no_stage", "no_stage_json", "no_summary_rows",
           "require_design"]

#: Margins named in a summary, smallest first.
SUMMARY_MARGINS = 3
#: Circumvents listed in a summary; the rest are counted.
SUMMARY_CIRCUMVENTS = 3

#: The reach-tube methods a design can use (``tube.method`` of the spec picks among them).
METHOD_PAPER = "paper"
METHOD_VIA = "via"


@dataclass(frozen=True)
class TubeCheck:
    """Outcome of :func:`~stt_codegen.design.search.check_tube` on a designed tube.

    Attributes
    ----------
    passed : bool
    reason : str
        Empty when passed, else the first failed condition in words.
    min_width : float
        Certified lower bound of ``min_t min_i gamma_d_i(t)``, state units.
    min_clearance : float
        Certified smallest separation of the tube box from an obstacle it must avoid
        (positive: clear), state units; ``inf`` without obstacles.
    max_move_ratio : float
        Certified bound of ``|gamma_dot| dt / gamma_d`` over all ``t``.
    initial_error : float
        ``max_i |e_i|`` of ``x(0)`` in the tube at ``t = 0``.
    certificate : Certificate
        The continuous-time certificate behind the verdict.
    kind : FailureKind or None
        What failed (``None`` when passed).
    """

    passed: bool
    reason: str
    min_width: float
    min_clearance: float
    max_move_ratio: float
    initial_error: float
    certificate: Certificate
    kind: FailureKind | None = None


@dataclass(frozen=True)
class Design:
    """A certified spatiotemporal tube for one spec.

    Attributes
    ----------
    tube : TubeDesign
        Every parameter the controller needs (reach segments, circumvents with their
        sharpness ``k^j``, ``nu``, eq. (11)'s parameters, gain ``k`` of law (13), rate).
    method : {"paper", "via"}
        ``"paper"``: one ``tanh`` reach segment (eq. (4)) with circumvents (7)-(9);
        ``"via"``: ``smoothstep`` segments through via boxes.
    check : TubeCheck
        The accepted tube's check (:func:`~stt_codegen.design.search.check_tube`),
        including its :class:`~stt_codegen.design.certificate.Certificate`.
    design_time_s : float
        In-process wall time of the whole :func:`~stt_codegen.design_tube` call, seconds:
        every alternative tried (``[target] any_of`` boxes, the slower tubes of
        ``[actuator]``) and every stage (the cascade's certification) included (not
        compared: two designs of one spec are equal).
    spec : Spec
        The spec the tube was designed for. ``generate``, ``simulate``, ``verify`` and the
        plots take a :class:`Design` and read its spec from here, so a tube cannot be
        paired with another spec's name, obstacles or plant.
    input_proof : InputProof or None
        For a spec with ``[actuator]``: the proved peak of each input of law (13) along
        the tube (:mod:`~stt_codegen.design.input_bound`), within ``input_bound``; for a
        second-order spec the sampled cascade's certified peak of each physical input
        (force or torque, :func:`~stt_codegen.design.cascade_gain.cascade_input_proof`);
        ``None`` otherwise.
    task_choices : tuple of int
        For a spec with ``[[tasks]]``: per task, the index of the box the tube was
        planned through (the ``any_of`` alternative; 0 for a single box); empty
        otherwise (docs/tasks.md).
    target_choice : int or None
        For a spec with ``[target] any_of``: the ``any_of`` index of the target box the
        tube ends in (``spec``'s target is that box); ``None`` otherwise.
    task_plan : TaskPlan or None
        For a spec with ``[[tasks]]``: the visit order and each task's hold, the interval
        over which ``rho`` holds its waypoint box (:mod:`~stt_codegen.design.tasks`).
    motion : str
        For a spec with moving obstacles: how the tube avoids them (``"space-time"``,
        ``"timed via"`` or ``"swept"``, :mod:`~stt_codegen.design.moving`); else ``""``.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> design.spec.name, design.method, design.gain == design.tube.gain
    ('omnirobot-s1', 'paper', True)
    >>> design.certificate.passed, design.input_proof is None
    (True, True)

    What it is, in a few lines (a notebook shows the same as a table,
    ``_repr_markdown_``):

    >>> design                                      # doctest: +ELLIPSIS
    Design(spec='omnirobot-s1', variant='first-order', method='paper', segments=1, circumvents=1, gain=0.1998, rate_hz=1000, certified=True, smallest_margin=0.0359)
    >>> print(design.summary())                     # doctest: +ELLIPSIS
    Design of omnirobot-s1: first-order (law (13)), the paper method, designed in ... s
      tube:             1 reach segment (tanh) to t_c = 9 s, 3 dimensions
      circumvents:      obstacle 0: x2 upper side on [0.321, 3.467] s, height 1.2, sharpness 0.1
      controller:       gain k = 0.1998, 1000 Hz
      certificate:      9 of 9 properties proved for every t >= 0 (... intervals)
      smallest margins: 0.03591 inside target after t_c (t = 7.617 s)
                        0.04668 non-empty (t = 0.4168 s)
                        0.05 initial state inside (t = 0 s)
    """

    tube: TubeDesign
    method: str
    check: TubeCheck
    design_time_s: float = field(compare=False)
    spec: Spec = field(compare=False, repr=False, kw_only=True)
    input_proof: InputProof | None = field(default=None, compare=False, repr=False,
                                           kw_only=True)
    task_choices: tuple[int, ...] = field(default=(), repr=False, kw_only=True)
    task_plan: TaskPlan | None = field(default=None, compare=False, repr=False, kw_only=True)
    target_choice: int | None = field(default=None, kw_only=True)
    motion: str = field(default="", compare=False, kw_only=True)

    @property
    def certificate(self) -> Certificate:
        """The continuous-time certificate of :attr:`tube` (every property, its margin)."""
        return self.check.certificate

    @property
    def gain(self) -> float:
        """``k`` of law (13)."""
        return self.tube.gain

    @cached_property
    def second_stage(self) -> tuple[SecondStage, dict]:
        """The cascade's certified second stage of a second-order design, and its derivation.

        The first shape of :data:`~stt_codegen.design.cascade_gain.SHAPES` whose sampled
        cascade is certified at the spec's rate
        (:func:`~stt_codegen.design.cascade_gain.second_stage_for`, computed once per tube;
        docs/second-order.md, "The sampled cascade").

        Returns
        -------
        stage : SecondStage
            ``k1``, ``k2`` and the velocity tube ``rho2``.
        derivation : dict
            As :func:`~stt_codegen.design.cascade_gain.derived_second_stage`, with the
            ``certificate``.

        Raises
        ------
        SpecError
            The spec's ``plant.model`` is first order (field ``plant.model``).
        DesignError
            No shape is certified at the design's rate (kind ``SAMPLING_RATE``).
        """
        return second_stage_for(self.tube, self.spec, self.check.min_width)

    @cached_property
    def output_warning(self) -> str | None:
        """Why the command of a design without ``[actuator]`` is not bounded by an
        actuator's range: the peak the certificate proves inside the declared class, and
        the deployed clamp's bound outside it (:mod:`~stt_codegen.design.output_bound`);
        ``None`` with ``[actuator] input_bound`` or for the first order's law (13).

        Returns
        -------
        str or None
            One sentence, in the spec's input names and unit.

        Examples
        --------
        >>> import stt_codegen as stt
        >>> design = stt.design_tube(stt.load_spec("second-order-s1"))
        >>> design.output_warning.split(":")[0]
        'no [actuator] input_bound'
        """
        spec = self.spec
        limits = (None if spec.input_bound is not None else
                  variant_of(spec).entry("output_limits")(self))
        if limits is None:
            return None
        unit = f" {spec.input_unit}" if spec.input_unit else ""
        inside = (", ".join(f"|{name}| <= {p:.4g}{unit}" for name, p in
                            zip(spec.input_names, limits.proved.peak))
                  if limits.proved.proved else "no bound (the sampled check fails)")
        outside = ", ".join(f"|{name}| <= {c:.3g}{unit}" for name, c in
                            zip(spec.input_names, limits.clamp))
        return (f"no [actuator] input_bound: {variant_of(spec).input_words} is proved "
                f"{inside} only for plants of the declared class; outside it (a heavier "
                f"plant, a contact, an undeclared delay) only the clamp of the errors "
                f"bounds it, {outside}; give [actuator] input_bound to have it proved "
                "within the actuator's range and clamped there")

    @property
    def look_ahead(self) -> LookAhead:
        """The look-ahead variant's data of a differential-drive design: the axle offset
        and the base's limits ``(v_max, omega_max)`` of ``[actuator] input_bound``
        (docs/differential-drive.md).

        Returns
        -------
        LookAhead

        Raises
        ------
        SpecError
            The spec's ``plant.model`` is not a differential drive (field ``plant.model``).
        """
        require_variant(self.spec, "look-ahead", "a look-ahead point")
        return LookAhead(self.spec.drive.axle_offset, self.spec.input_bound,
                         self.spec.reverse_speed)

    @property
    def stage(self) -> SecondStage | LookAhead | None:
        """What the controller variant needs beyond the tube: ``None`` for law (13) on the
        plant's state, the cascade's :attr:`second_stage`, the :attr:`look_ahead` point.

        Returns
        -------
        SecondStage, LookAhead or None

        Raises
        ------
        DesignError
            A second-order design whose second stage is not certified.
        """
        return variant_of(self.spec).entry("stage")(self)

    def tube_table(self, horizon: float | None = None) -> dict[str, np.ndarray]:
        """The deployed tube at every sampling instant of the controller, as columns.

        ``alpha`` follows the deployed implicit step of law (11) from ``alpha(0) = 0`` at
        ``rate_hz`` (:func:`~stt_codegen.design.samples.sample_tube`, the tube the
        simulation and the backends' tests use), and ``gamma`` is eq. (10) at it. What
        ``stt-codegen design --export`` writes.

        Parameters
        ----------
        horizon : float, optional
            End time, s; default ``1.1 t_c`` (:data:`~stt_codegen.design.samples.HORIZON_FACTOR`).

        Returns
        -------
        dict of str to ndarray, each of shape (N,)
            ``"t"``: the instants ``k / rate_hz``, s, from 0, ``N = ceil(horizon rate_hz) +
            1``; then ``"gamma_L_i"`` and ``"gamma_U_i"`` for each axis ``i = 1..n`` (the
            tube's lower and upper bound of ``x_i``, state units), in that order.

        Raises
        ------
        SpecError
            ``horizon`` is not a positive number (field ``horizon``), or the table would
            have more than :data:`~stt_codegen.design.samples.STEP_BUDGET` rows.

        Examples
        --------
        >>> import stt_codegen as stt
        >>> table = stt.design_tube(stt.load_spec("omnirobot-s1")).tube_table(horizon=1.0)
        >>> list(table)[:3], table["t"].shape, table["t"][:2]
        (['t', 'gamma_L_1', 'gamma_U_1'], (1001,), array([0.   , 0.001]))
        """
        if horizon is not None and not (isinstance(horizon, (int, float, np.number))
                                        and not isinstance(horizon, bool)
                                        and math.isfinite(horizon) and horizon > 0):
            raise SpecError("horizon", f"must be a positive number of seconds, got "
                                       f"{horizon!r}")
        samples = sample_tube(self.tube, None if horizon is None else float(horizon))
        table = {"t": samples.t}
        for i in range(self.tube.dimension):
            table[f"gamma_L_{i + 1}"] = samples.gamma_lower[:, i]
            table[f"gamma_U_{i + 1}"] = samples.gamma_upper[:, i]
        return table

    def summary_rows(self) -> Rows:
        """The rows of :meth:`summary`: ``(label, value)`` in words.

        Returns
        -------
        list of (str, str)
            The tube, the circumvents, the controller, the certificate and its smallest
            margins, the proved input peaks (``[actuator]``), the variant's own rows
            (role ``summary_rows`` of :mod:`~stt_codegen.spec.variants`), the target
            chosen, the tasks and the moving obstacles, where the design has them.
        """
        tube, spec, cert = self.tube, self.spec, self.certificate
        profiles = ", ".join(sorted({s.profile for s in tube.segments}))
        count = len(tube.segments)
        rows = [("tube", f"{count} reach segment{'s' * (count != 1)} ({profiles}) to "
                         f"t_c = {spec.prescribed_time:g} s, {tube.dimension} dimensions")]
        if tube.circumvents:
            shown = [f"obstacle {c.obstacle}: x{c.dimension + 1} {c.side} side on "
                     f"[{c.start:.3f}, {c.end:.3f}] s, height {c.height:.3g}, sharpness "
                     f"{c.sharpness:g}" for c in tube.circumvents[:SUMMARY_CIRCUMVENTS]]
            more = len(tube.circumvents) - SUMMARY_CIRCUMVENTS
            rows += [("circumvents" if k == 0 else "", line) for k, line in enumerate(shown)]
            if more > 0:
                rows.append(("", f"{more} more (design.tube.circumvents)"))
        rows.append(("controller", f"gain k = {tube.gain:.4g}, {tube.rate_hz:g} Hz"))
        proved = sum(m.passed for m in cert.margins)
        horizon = "every t >= 0" if math.isinf(cert.horizon) else f"t <= {cert.horizon:g} s"
        rows.append(("certificate", f"{proved} of {len(cert.margins)} properties proved for "
                                    f"{horizon} ({cert.intervals} intervals)"))
        smallest = sorted(cert.margins, key=lambda m: m.margin)[:SUMMARY_MARGINS]
        rows += [("smallest margins" if k == 0 else "",
                  f"{m.margin:.4g} {m.name} (t = {m.time:.4g} s)"
                  + ("" if m.passed else " FAILED")) for k, m in enumerate(smallest)]
        if self.input_proof is not None and spec.input_bound is not None:
            unit = f" {spec.input_unit}" if spec.input_unit else ""
            rows.append(("proved input peaks", ", ".join(
                f"|{name}| {p:.4g} <= {b:g}{unit}" for name, p, b in
                zip(spec.input_names, self.input_proof.peak, spec.input_bound))
                + f" (samples to t = {self.input_proof.horizon:g} s)"))
        rows += variant_of(spec).entry("summary_rows")(self)
        if self.output_warning is not None:
            rows.append(("warning", self.output_warning))
        if self.target_choice is not None:
            rows.append(("target", f"any_of[{self.target_choice}]"))
        if spec.tasks:
            order = "" if self.task_plan is None else " in the order " + ", ".join(
                spec.tasks[k].label for k in self.task_plan.order)
            rows.append(("tasks", f"{len(spec.tasks)} planned{order}"))
        if self.motion:
            rows.append(("moving obstacles", f"{len(spec.moving_obstacles)} avoided "
                                             f"({self.motion})"))
        return rows

    def summary(self) -> str:
        """The design in at most 20 lines: the method, the tube, the circumvents, the gain
        and rate, the certificate with its smallest margins, the proved input peaks and
        the variant's stage.

        Returns
        -------
        str
            A title line, then one line a row of :meth:`summary_rows`.

        Examples
        --------
        >>> import stt_codegen as stt
        >>> design = stt.design_tube(stt.load_spec("second-order-s1"))
        >>> print(design.summary())                 # doctest: +ELLIPSIS
        Design of second-order-s1: cascade (the cascade's input u), the via method, ...
          tube:             3 reach segments (smoothstep) to t_c = 9 s, 2 dimensions
          controller:       gain k = 2.46, 1000 Hz
          certificate:      9 of 9 properties proved for every t >= 0 (... intervals)
          smallest margins: 0.03078 inside target after t_c (t = 8.708 s)
                            0.03606 avoids obstacle 0 (t = 0 s)
                            0.05158 inside state space (t = 0 s)
          second stage:     k1 = 0.04724, k2 = 11.98, velocity tube rho2 from 0.4506 to ...
          sampled cascade:  certified: position margin 0.44, velocity margin 0.772
                            peak input |F1| 3.292 N, |F2| 5.394 N
        """
        return text(self._title(), self.summary_rows())

    def _title(self) -> str:
        variant = variant_of(self.spec)
        return (f"Design of {self.spec.name}: {variant.name} ({variant.input_words}), the "
                f"{self.method} method, designed in {self.design_time_s:.3g} s")

    def _repr_markdown_(self) -> str:
        """The summary as a Markdown table (Jupyter's rich display)."""
        return markdown(self._title(), self.summary_rows())

    def __repr__(self) -> str:
        smallest = min((m.margin for m in self.certificate.margins), default=math.inf)
        return (f"Design(spec={self.spec.name!r}, variant={variant_of(self.spec).name!r}, "
                f"method={self.method!r}, segments={len(self.tube.segments)}, "
                f"circumvents={len(self.tube.circumvents)}, gain={self.tube.gain:.4g}, "
                f"rate_hz={self.tube.rate_hz:g}, certified={self.certificate.passed}, "
                f"smallest_margin={smallest:.3g})")

    def to_json(self) -> dict[str, Any]:
        """The design as plain JSON types (the ``design`` command's and ``simulate --json``'s).

        Returns
        -------
        dict
            ``spec`` (the name of :attr:`spec`), ``designed`` (``True``; the command
            line's document for a spec with no design has ``False``), ``method``,
            ``circumvents`` (spec obstacle index, dimension, side, window start and end in
            s, height, sharpness), ``via`` (boxes and times; empty for the paper's
            method), ``segments``, ``gain``, ``timing`` (``rate_hz``, ``period_s``,
            ``delay_s``, ``jitter_s``: the loop the certificate covers, as the generated
            header's timing contract), ``certificate`` (each property with its margin and
            where it is smallest) and ``design_time_s``; for a spec with
            ``[actuator]`` also ``input_bound`` and ``input_peak`` (the proved peak of
            each input, when it occurs, the horizon covered, the relative margin); for a
            spec with moving obstacles also ``motion`` and ``moving_obstacles`` (index,
            motion, active interval, the task it lasts until or ``None``, certified
            margin; docs/moving-obstacles.md); for a
            spec with a second-order ``plant.model`` also ``cascade`` (``gains``: the
            certified second stage's derivation and its sampled-data certificate,
            :func:`~stt_codegen.design.cascade_gain.second_stage_of`); for a spec with
            ``[robot]`` also ``robot`` (the radius, the state space as given and shrunk,
            the inflated obstacle boxes: :func:`~stt_codegen.spec.robot.robot_json`);
            ``warnings`` (a list: :attr:`output_warning` where there is one).
        """
        tube = self.tube
        via = []
        if self.method != METHOD_PAPER:
            segs = tube.segments
            via = [{"time": segs[0].start, "lower": list(segs[0].lower_from),
                    "upper": list(segs[0].upper_from)}]
            via += [{"time": s.end, "lower": list(s.lower_to), "upper": list(s.upper_to)}
                    for s in segs]
        return {
            "spec": self.spec.name,
            "designed": True,
            "method": self.method,
            "circumvents": [{"obstacle": c.obstacle, "dimension": c.dimension,
                             "side": c.side, "start": c.start, "end": c.end,
                             "height": c.height, "sharpness": c.sharpness}
                            for c in tube.circumvents],
            "via": via,
            "segments": [{"start": s.start, "end": s.end, "profile": s.profile}
                         for s in tube.segments],
            "gain": tube.gain,
            "timing": {"rate_hz": tube.rate_hz, "period_s": 1.0 / tube.rate_hz,
                       "delay_s": self.spec.delay, "jitter_s": self.spec.jitter},
            "certificate": {
                "passed": self.certificate.passed,
                "horizon": "inf" if math.isinf(self.certificate.horizon)
                else self.certificate.horizon,
                "intervals": self.certificate.intervals,
                "properties": [{"name": m.name, "passed": m.passed, "margin": m.margin,
                                "time": m.time, "detail": m.detail}
                               for m in self.certificate.margins],
            },
            "design_time_s": self.design_time_s,
            "warnings": [] if self.output_warning is None else [self.output_warning],
            **self._actuator_json(),
            **self._tasks_json(),
            **self._target_json(),
            **self._motion_json(),
            **self._stage_json(),
            **robot_json(self.spec),
        }

    def _target_json(self) -> dict[str, Any]:
        """``target_choice``: for a spec with ``[target] any_of`` only, the box the tube
        ends in and the boxes dropped (an obstacle meets them)."""
        if self.target_choice is None:
            return {}
        return {"target_choice": {
            "alternative": self.target_choice,
            "lower": list(self.spec.target_set.lower),
            "upper": list(self.spec.target_set.upper),
            "dropped": [{"any_of": q, "obstacle": name}
                        for q, name in self.spec.target_dropped]}}

    def _tasks_json(self) -> dict[str, Any]:
        """``tasks``: per ``[[tasks]]`` entry its label, kind, window, the box planned
        through (``alternative``, its corners) and the certified margin; for a spec with
        tasks only: without them the document is as before."""
        if not self.spec.tasks:
            return {}
        margins = {m.name: m for m in self.certificate.margins}
        out = []
        plan = self.task_plan
        for k, (task, q) in enumerate(zip(self.spec.tasks, self.task_choices)):
            m = margins.get(task.name)
            out.append({"task": task.label, "kind": task.kind, "window": list(task.window),
                        "duration": task.duration,
                        "alternative": task.any_of_index[q],
                        "dropped": [{"any_of": i, "obstacle": o} for i, o in task.dropped],
                        "lower": list(task.boxes[q].lower),
                        "upper": list(task.boxes[q].upper),
                        "visit": None if plan is None else plan.order.index(k) + 1,
                        "hold": None if plan is None else list(plan.holds[k]),
                        "certified": bool(m is not None and m.passed),
                        "margin": None if m is None else m.margin})
        return {"tasks": out}

    def _motion_json(self) -> dict[str, Any]:
        """``motion`` and ``moving_obstacles`` (each with its certified margin), for a spec
        with moving obstacles only: without them the document is as before."""
        if not self.spec.moving_obstacles:
            return {}
        margins = {m.name: m for m in self.certificate.margins}
        return {"motion": self.motion, "moving_obstacles": [
            {"obstacle": ob.source, "motion": ob.motion, "active": [
                ob.active[0], "inf" if math.isinf(ob.active[1]) else ob.active[1]],
             "until": None if ob.until is None else self.spec.tasks[ob.until].label,
             "margin": margins[f"avoids moving obstacle {ob.source}"].margin}
            for ob in self.spec.moving_obstacles]}

    def _stage_json(self) -> dict[str, Any]:
        """The variant's own fields (``cascade``: the certified second stage's derivation
        with its sampled-data certificate, for a second-order spec only): without them the
        document is as before."""
        return variant_of(self.spec).entry("stage_json")(self)

    def _actuator_json(self) -> dict[str, Any]:
        """``input_bound`` and the proved ``input_peak`` (with where each peak is), for a
        spec with ``[actuator]`` only: without it the document is as before."""
        if self.spec.input_bound is None or self.input_proof is None:
            return {}
        proof, bound = self.input_proof, self.spec.input_bound
        return {"input_bound": list(bound),
                "input_peak": {"peak": list(proof.peak), "time": list(proof.time),
                               "horizon": proof.horizon, "margin": proof.margin(bound)}}


def require_design(value: object, function: str, parameter: str = "design") -> Design:
    """``value``, checked to be a :class:`Design`: the front door's functions take the
    design object itself, which carries its spec, so that a tube cannot be paired with
    another spec's name, obstacles or plant.

    Parameters
    ----------
    value : object
        What the caller passed as ``parameter``.
    function : str
        The public function's name, for the message (``"simulate"``).
    parameter : str
        The parameter's name, for the message.

    Returns
    -------
    Design
        ``value``.

    Raises
    ------
    TypeError
        ``value`` is not a ``Design`` (a ``TubeDesign``, a ``Spec``, ...); the message
        names the parameter and says to call ``design_tube``.
    """
    if isinstance(value, Design):
        return value
    kind = type(value).__name__
    if isinstance(value, TubeDesign):
        hint = ("this is design.tube; pass the Design that stt_codegen.design_tube(spec) "
                "returned, which carries its spec")
    else:
        hint = "call stt_codegen.design_tube(spec) and pass the Design it returns"
    raise TypeError(f"{function}(): parameter {parameter!r} must be a Design, not {kind}; "
                    f"{hint}")


def no_stage(design: Design) -> None:
    """The stage of law (13) on the plant's state (the first-order variant's role
    ``stage``, :mod:`~stt_codegen.spec.variants`): none.

    Parameters
    ----------
    design : Design
    """
    return None


def cascade_stage(design: Design) -> SecondStage:
    """The cascade's stage: :attr:`Design.second_stage` (role ``stage``).

    Parameters
    ----------
    design : Design

    Returns
    -------
    SecondStage

    Raises
    ------
    DesignError
        The second stage is not certified.
    """
    return design.second_stage[0]


def look_ahead_stage(design: Design) -> LookAhead:
    """The look-ahead variant's stage: :attr:`Design.look_ahead` (role ``stage``).

    Parameters
    ----------
    design : Design

    Returns
    -------
    LookAhead
    """
    return design.look_ahead


def no_stage_json(design: Design) -> dict[str, Any]:
    """The design document's fields of a variant without a derived stage (role
    ``stage_json``): none, so the document is as without a variant.

    Parameters
    ----------
    design : Design

    Returns
    -------
    dict
        Empty.
    """
    return {}


def cascade_stage_json(design: Design) -> dict[str, Any]:
    """``cascade``: the certified second stage's derivation with its sampled-data
    certificate (``gains``), the cascade's role ``stage_json``.

    Parameters
    ----------
    design : Design

    Returns
    -------
    dict
        ``{"cascade": {"gains": ...}}``.
    """
    return {"cascade": {"gains": design.second_stage[1]}}


def no_summary_rows(design: Design) -> list[tuple[str, str]]:
    """The summary rows of a variant without a stage (role ``summary_rows``): none.

    Parameters
    ----------
    design : Design

    Returns
    -------
    list of (str, str)
        Empty.
    """
    return []


def cascade_summary_rows(design: Design) -> list[tuple[str, str]]:
    """The cascade's rows of :meth:`Design.summary` (role ``summary_rows``): its certified
    second stage and the sampled cascade's figures.

    Parameters
    ----------
    design : Design

    Returns
    -------
    list of (str, str)
        ``second stage`` (``k1``, ``k2``, the velocity tube ``rho2``) and ``sampled
        cascade`` (its margins, then the certified peak of each physical input).
    """
    stage, derivation = design.second_stage
    cert = derivation["certificate"]
    unit = f" {design.spec.input_unit}" if design.spec.input_unit else ""
    peaks = ", ".join(f"|{name}| {p:.4g}{unit}" for name, p in
                      zip(design.spec.input_names, cert["peak_input"]))
    return [("second stage", f"k1 = {stage.position_gain:.4g}, k2 = "
                             f"{stage.velocity_gain:.4g}, velocity tube rho2 from "
                             f"{max(stage.width_start):.4g} to {max(stage.width_floor):.4g} "
                             f"(decay {stage.decay:g} /s)"),
            ("sampled cascade", f"certified: position margin {cert['position_margin']:.3g}, "
                                f"velocity margin {cert['velocity_margin']:.3g}"),
            ("", f"peak input {peaks}")]


def look_ahead_summary_rows(design: Design) -> list[tuple[str, str]]:
    """The look-ahead variant's row of :meth:`Design.summary` (role ``summary_rows``):
    the point law (13) holds and the base's limits.

    Parameters
    ----------
    design : Design

    Returns
    -------
    list of (str, str)
        ``look-ahead point``.
    """
    point = design.look_ahead
    limits = ("no limits" if point.input_bound is None else
              f"limits v <= {point.input_bound[0]:g}, omega <= {point.input_bound[1]:g}")
    return [("look-ahead point", f"l = {point.axle_offset:g} ahead of the axle (law (13) "
                                 f"holds it); the base's {limits}")]
