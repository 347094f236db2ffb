"""Standalone C and Python of the cascade controller for second-order plants.

The entry point has every variant's signature, ``<prefix>_step(x, t, dt, alpha, u,
alpha_next) -> status`` with ``x = [x1; x2]``, and the first order's statuses (plus
``OUTSIDE_VELOCITY_TUBE``); the virtual velocity is the accessor
``<prefix>_virtual_velocity(x, t, alpha, r) -> status``. Both compute
:func:`stt_codegen.tube.cascade.cascade_step` of a design and its second stage, bit for bit
in double precision.

* C: a variant of the first-order source (:func:`.generate.c_source_context`,
  ``c_source.c.j2``): the same tables and table-driven tube (only the active segment and
  the open circumvents), ``P_tube``, ``P_alpha_step`` and input checks, with the cascade's
  law (``cascade_source.c.j2``: the first order's ``law`` piece with gain ``k1`` for
  ``r``, the pieces ``velocity_tube`` and ``velocity_law``, the first order's
  ``saturate`` with an actuator bound) and the second stage's numbers in a ``const``
  table. C99, ``<math.h>`` and ``<stddef.h>`` only, no allocation, no static mutable
  state.
* Python: the composed Function printed whole by the emitter's Python printer, behind the
  first order's input checks.

Deterministic text (docs/second-order.md, "Generated code"). This module only prepares
the data: the bodies the emitter prints, the names, the constants (as the printer's
literals) and the banner's fields. The text of the files is in the Jinja2 templates
``cascade_header.h.j2``, ``cascade_source.c.j2`` and ``cascade_module.py.j2`` (with the
banner ``_banner_cascade.j2``) of the top-level ``templates/``, rendered through
:func:`.render.render` as the first-order files are.
"""

from __future__ import annotations

import dataclasses
import hashlib

import casadi

from ..tube.cascade import cascade_step, velocity_law, velocity_tube
from ..tube.model import build_model
from ..tube.parameters import Status, TubeDesign, step_status
from ..tube.second_stage import SecondStage
from ..version import __version__
from ..design.output_bound import cascade_clamp
from ..design.prediction import delay_predictor
from ..design.result import Design
from .emit import lower, python_source
from .functions import deployed_functions
from .generate import c_source_context, input_limits, timing_context
from .options import Options
from .render import c_real, render

__all__ = ["cascade_c_files", "cascade_generation", "cascade_python_file", "statuses"]

def design_hash(design: TubeDesign, stage: SecondStage) -> str:
    """SHA-256 of the design's and the stage's numbers (their ``repr``), hex."""
    return hashlib.sha256((repr(design) + repr(stage)).encode()).hexdigest()


def statuses(design: TubeDesign) -> list[tuple[str, int]]:
    """The status names and codes the cascade's generated code defines, in code order: the
    first order's (:class:`~stt_codegen.tube.parameters.Status`; ``INPUT_CLAMPED`` only
    with an actuator bound) and ``OUTSIDE_VELOCITY_TUBE``.

    Parameters
    ----------
    design : TubeDesign
        The position tube; its ``input_bound`` decides whether ``INPUT_CLAMPED`` is one.

    Returns
    -------
    list of (str, int)
        ``(name, code)`` pairs, by code.
    """
    return [(s.name, int(s)) for s in Status
            if s != Status.INPUT_CLAMPED or design.input_bound is not None]


def _context(design: TubeDesign, stage: SecondStage, prefix: str, precision: str,
             literal, timing: tuple[float, float] = (0.0, 0.0)) -> dict:
    """What every cascade template takes: the banner's fields, the names, the statuses,
    the input domain's limits (those of the first order, :func:`.generate.input_limits`)
    and the actuator bound, printed by ``literal``."""
    limits = input_limits(design)
    return {"spec_name": design.name, "design_hash": design_hash(design, stage),
            "toolkit_version": __version__, "casadi_version": casadi.__version__,
            "precision": precision, "P": prefix, "U": prefix.upper(),
            "n": design.dimension, "statuses": statuses(design),
            "t_c": literal(design.prescribed_time), "rate_hz": literal(design.rate_hz),
            **timing_context(design.rate_hz, timing, literal),
            **{name: literal(value) for name, value in limits.items()},
            "input_bound": (None if design.input_bound is None else
                            [literal(b) for b in design.input_bound]),
            # without a bound: what the clamp of the errors allows, in words (3 digits)
            "output_clamp": (None if design.input_bound is not None else
                             [f"{c:.3g}" for c in cascade_clamp(stage)])}


def cascade_c_files(design: TubeDesign, stage: SecondStage, prefix: str,
                    precision: str = "double", timing: tuple[float, float] = (0.0, 0.0),
                    predictor: casadi.Function | None = None) -> dict[str, str]:
    """``{<prefix>.h: text, <prefix>.c: text}`` of the cascade controller.

    The emitter's C printer prints the pieces (the first order's and the cascade's); the
    templates ``cascade_header.h.j2`` and ``cascade_source.c.j2`` (which extends the
    first-order ``c_source.c.j2``) hold the rest of the text.

    Parameters
    ----------
    design : TubeDesign
        The position tube.
    stage : SecondStage
        Of the same dimension.
    prefix : str
        A C identifier: the file names and the prefix of every public name.
    precision : {"double", "single"}
    timing : (float, float)
        ``(delay, jitter)`` of the spec, s: the header's timing contract.
    predictor : casadi.Function, optional
        With ``[controller] compensate_delay``, the spec's
        :func:`~stt_codegen.design.prediction.delay_predictor`: ``P_predict`` is generated.

    Returns
    -------
    dict of str to str
        Deterministic for given arguments, CasADi and toolkit versions.

    Raises
    ------
    ValueError
        ``prefix`` not a C identifier, or ``stage`` of another dimension.
    """
    if not prefix.isidentifier() or not prefix.isascii():
        raise ValueError(f"prefix {prefix!r} is not a C identifier")
    if stage.dimension != design.dimension:
        raise ValueError(f"second stage of dimension {stage.dimension} for a tube of "
                         f"dimension {design.dimension}")
    single = precision == "single"
    literal = lambda v: c_real(v, single)  # noqa: E731
    # the tube's tables carry k1 as law (13)'s gain: r is law (13) with gain k1
    first = dataclasses.replace(design, gain=stage.position_gain)
    functions = [*deployed_functions(build_model(first)), velocity_tube(design.dimension),
                 velocity_law(design.dimension),
                 *([predictor] if predictor is not None else [])]
    context = dict(c_source_context(first, prefix, precision, functions),
                   **_context(design, stage, prefix, precision, literal, timing),
                   cascade=True, predict=predictor is not None,
                   stage={"velocity_gain": literal(stage.velocity_gain),
                          "decay": literal(stage.decay),
                          "width_start": [literal(v) for v in stage.width_start],
                          "width_floor": [literal(v) for v in stage.width_floor]})
    return {name: render(template, filename=name, **context)
            for name, template in ((f"{prefix}.h", "cascade_header.h.j2"),
                                   (f"{prefix}.c", "cascade_source.c.j2"))}


def cascade_python_file(design: TubeDesign, stage: SecondStage, prefix: str,
                        timing: tuple[float, float] = (0.0, 0.0),
                        predictor: casadi.Function | None = None) -> dict[str, str]:
    """``{<prefix>.py: text}``: ``step(x, t, dt, alpha) -> (u, alpha_next, status)`` and
    ``virtual_velocity(x, t, alpha) -> (r, status)`` (``x = [x1; x2]``), the same functions,
    statuses and input checks as the C (imports ``math`` only). The emitter's Python printer prints the composed Function; the template
    ``cascade_module.py.j2`` holds the rest of the text.

    Parameters
    ----------
    design : TubeDesign
        The first stage's tube (positions).
    stage : SecondStage
        The second stage (velocity tube and gains), of the design's dimension.
    prefix : str
        Module name, an ASCII identifier.
    timing : (float, float)
        ``(delay, jitter)`` of the spec, s: the module's ``DELAY`` and ``JITTER``.
    predictor : casadi.Function, optional
        As :func:`cascade_c_files`: ``predict(x, u_held)`` is generated.

    Returns
    -------
    dict of str to str
        One entry, ``<prefix>.py`` and its text.

    Raises
    ------
    ValueError
        ``prefix`` not an identifier, or ``stage`` of another dimension.
    """
    if not prefix.isidentifier() or not prefix.isascii():
        raise ValueError(f"prefix {prefix!r} is not an identifier")
    name = f"{prefix}.py"
    return {name: render("cascade_module.py.j2", filename=name,
                         **_context(design, stage, prefix, "double",
                                    lambda v: repr(float(v)), timing),
                         predict=predictor is not None,
                         body=python_source([lower(cascade_step(design, stage)), *(
                             [dataclasses.replace(lower(predictor), name="body_predict")]
                             if predictor is not None else [])]))}


#: Test vectors per generation: sample points of the cascade step.
VECTOR_COUNT = 64


def cascade_vectors(design: TubeDesign, stage: SecondStage, count: int = VECTOR_COUNT,
                    precision: str = "double") -> dict:
    """Test vectors of the cascade step from the numpy oracle (JSON-ready, deterministic).

    Points: ``t`` spread over ``[0, 1.1 t_c]`` where the tube at ``alpha = 0`` is at least
    1e-3 wide, ``alpha = 0``, ``dt`` the design's period (the document's ``dt``),
    ``x1`` inside the position tube (``|e1| <= 0.9``), ``x2 = r + rho2 s`` with ``|s| <=
    0.9``, from a fixed seed; ``t``, ``dt``, ``x1`` and ``x2`` are float32 numbers (exact in
    both precisions, as the first-order vectors). Expected ``u``, ``r``, ``alpha_next`` and
    status from :func:`stt_codegen.tube.cascade_reference.cascade_step`, the tube
    ``gamma_L``, ``gamma_U`` at ``(t, alpha)`` from the oracle's adaptive tube; absolute
    tolerances ``tol_u``, ``tol_r``, ``tol_alpha_next`` from
    :func:`stt_codegen.codegen.tolerance.cascade_bounds` and ``tol_gamma`` from
    :func:`~stt_codegen.codegen.tolerance.gamma_bound` (the first order's) for
    ``precision`` (double: with the floor ``1e-12 max(1, |ref|)``). With an actuator bound, the expected status is ``OK``
    or ``INPUT_CLAMPED`` as the oracle clamps, and only points whose clamp decision is
    certain in the precision are kept (every ``|u_i|`` of the law farther from the bound
    than its tolerance plus the bound's rounding), as for the first order. Then the copies
    of :func:`.vectors.period_copies`: a point of the law's status ``OK`` (and one of
    ``INPUT_CLAMPED``) again at ``dt = 1.5 PERIOD``, the step's status ``OFF_PERIOD``; each
    vector has its own ``dt``.

    Raises
    ------
    SpecError
        ``precision``: it cannot resolve the position tube at the spec's coordinates (the
        first order's test, :func:`.vectors.sample_inputs`, on the same tube).
    """
    import numpy as np

    from ..rounding import round_up_array
    from ..tube import cascade_reference, reference
    from . import tolerance as T
    from .vectors import period_copies, sample_inputs

    sample_inputs(design, precision)      # raises SpecError where the precision cannot
    #                                       resolve the position tube (its points unused)

    def f32(a):
        return np.asarray(a, dtype=np.float32).astype(np.float64)

    rng = np.random.default_rng(22)
    n = design.dimension
    t = f32(np.linspace(0.0, 1.1 * design.prescribed_time, 4 * count))
    dt = float(np.float32(1.0 / design.rate_hz))
    alpha = np.zeros((t.size, 2 * n))
    g_l, g_u, _, _ = reference.adaptive_tube(design, t, alpha)
    # where the tube at alpha = 0 is at least 1e-3 wide (where bumps conflict it is empty
    # until alpha grows), every 4th such time
    keep = np.flatnonzero(np.all(g_u - g_l > 1e-3, axis=1))[::4][:count]
    t, alpha, g_l, g_u = t[keep], alpha[keep], g_l[keep], g_u[keep]
    count = t.size
    x1 = f32((g_u + g_l) / 2 + (g_u - g_l) / 2 * rng.uniform(-0.9, 0.9, (count, n)))
    _, _, r, *_ = cascade_reference.cascade_step(design, stage,
                                                 np.hstack([x1, np.zeros((count, n))]),
                                                 t, dt, alpha)
    rho2 = cascade_reference.velocity_tube(stage, t)
    x2 = f32(r + rho2 * rng.uniform(-0.9, 0.9, (count, n)))
    unit = T.unit_roundoff(precision)

    def outputs(t, x1, x2, alpha, dt):
        # the oracle's outputs, the law's and the step's status, every tolerance
        u, alpha_next, r, inside_p, inside_v, within = cascade_reference.cascade_step(
            design, stage, np.hstack([x1, x2]), t, dt, alpha)
        law = np.where(inside_p == 0, Status.OUTSIDE_TUBE,
                       np.where(inside_v == 0, Status.OUTSIDE_VELOCITY_TUBE,
                                np.where(within == 0, Status.INPUT_CLAMPED, Status.OK)))
        g_l, g_u, _, _ = reference.adaptive_tube(design, t, alpha)
        tol_u, tol_r, tol_a = T.cascade_bounds(design, stage, x1, x2, t, alpha, r, alpha_next,
                                               unit)
        # the tube's bound, as the first order's P_tube (vectors.vector_document)
        tol_g = np.broadcast_to(T.gamma_bound(design, alpha, unit), g_l.shape)
        if precision == "double":
            tol_u, tol_r, tol_a = (T.with_double_floor(tol, ref) for tol, ref in
                                   ((tol_u, u), (tol_r, r), (tol_a, alpha_next)))
            tol_g = T.with_double_floor(tol_g, np.maximum(np.abs(g_l), np.abs(g_u)))
        # rounded up to a few digits: still bounds, and the same on every CPU (docs/codegen.md)
        tol_u, tol_r, tol_a, tol_g = (round_up_array(tol) for tol in (tol_u, tol_r, tol_a, tol_g))
        return {"t": t, "x1": x1, "x2": x2, "alpha": alpha, "dt": dt, "u": u, "r": r,
                "alpha_next": alpha_next, "law": law,
                "status": step_status(law, dt, design.rate_hz), "gamma_L": g_l,
                "gamma_U": g_u, "tol_u": tol_u, "tol_r": tol_r, "tol_alpha_next": tol_a,
                "tol_gamma": tol_g}

    rows = outputs(t, x1, x2, alpha, np.full(t.shape, dt))
    if design.input_bound is not None:
        # only points whose clamp decision is certain in the precision: every |u_i| of the
        # law farther from the bound than its error bound plus the bound's rounding (the
        # first order's rule, docs/codegen.md "Actuator limits: the clamp")
        free = cascade_reference.cascade_step(dataclasses.replace(design, input_bound=None),
                                              stage, np.hstack([x1, x2]), t, dt, alpha)[0]
        bound = np.asarray(design.input_bound)
        keep = np.all(np.abs(np.abs(free) - bound) > rows["tol_u"] + 2 * unit * bound, axis=1)
        rows = {k: v[keep] for k, v in rows.items()}
    # every vector is at the period: copies off it (vectors.period_copies), with the same
    # u, r and law's status, alpha_next at their dt and the step's status OFF_PERIOD
    copied, steps = period_copies(rows["dt"], rows["law"], design.rate_hz)
    if copied.size:
        extra = outputs(*(rows[k][copied] for k in ("t", "x1", "x2", "alpha")), steps)
        rows = {k: np.concatenate([v, extra[k]]) for k, v in rows.items()}
    count = rows["t"].size
    return {"_generated": "GENERATED FILE, DO NOT EDIT: cascade test vectors from the numpy "
                          "reference (stt_codegen.tube.cascade_reference).",
            "dt": dt, "precision": precision, "unit_roundoff": unit,
            "vectors": [{"t": float(rows["t"][k]), "dt": float(rows["dt"][k]),
                         "x": [*rows["x1"][k].tolist(), *rows["x2"][k].tolist()],
                         **{key: rows[key][k].tolist() for key in ("alpha", "u", "r",
                                                                    "alpha_next")},
                         "status": int(rows["status"][k]),
                         **{key: rows[key][k].tolist() for key in (
                             "gamma_L", "gamma_U", "tol_u", "tol_r", "tol_alpha_next",
                             "tol_gamma")}}
                        for k in range(count)]}


def cascade_generation(design: Design, options: Options) -> dict[str, bytes]:
    """Every file of the cascade controller of a second-order design, in memory.

    The file set of every variant (:mod:`.fileset`), ``P`` the spec's C name: ``P.h``,
    ``P.c``, ``P_selftest.c`` (the vectors replayed through ``P_step``,
    ``P_virtual_velocity`` and ``P_alpha_step``), ``Makefile`` and ``CMakeLists.txt`` (with
    ``"c"`` in ``options.langs``, in ``options.precision``), ``P.py`` (with ``"python"``),
    ``P_vectors.json`` (:func:`cascade_vectors`) and ``manifest.json``. The second stage is
    the default one of :attr:`stt_codegen.design.result.Design.second_stage`.

    Parameters
    ----------
    design : Design
        Of a spec with a second-order ``plant.model``.
    options : Options

    Returns
    -------
    dict of str to bytes

    Raises
    ------
    SpecError
        A first-order spec (field ``plant.model``).
    """
    from .fileset import build_files, file_context, json_bytes, selftest_file, with_manifest

    stage, _ = design.second_stage
    spec = design.spec
    predictor = delay_predictor(spec, design.tube, stage)
    context = file_context(spec, options.precision)
    prefix = context["P"]
    data = cascade_vectors(design.tube, stage, precision=options.precision)
    texts: dict[str, str] = {}
    if "c" in options.langs:
        texts.update(cascade_c_files(design.tube, stage, prefix, options.precision,
                                     (spec.delay, spec.jitter), predictor))
        texts.update(build_files(context))
        rows = data["vectors"]
        inputs = {"x": [v["x"] for v in rows], "t": [v["t"] for v in rows],
                  "dt": [v["dt"] for v in rows], "alpha": [v["alpha"] for v in rows],
                  "status": [v["status"] for v in rows]}
        names = ("u", "alpha_next", "r", "gamma_L", "gamma_U")
        expected = [(f"EXP_{k.upper()}", [v[k] for v in rows], len(rows[0][k])) for k in names]
        expected += [(f"TOL_{k.upper()}", [v[f"tol_{k}"] for v in rows],
                      len(rows[0][f"tol_{k}"]))
                     for k in ("u", "alpha_next", "r", "gamma")]
        texts.update(selftest_file(context, inputs, expected, options.precision,
                                   "cascade_selftest.c.j2"))
    if "python" in options.langs:
        texts.update(cascade_python_file(design.tube, stage, prefix, (spec.delay, spec.jitter),
                                         predictor))
    files = {name: text.encode() for name, text in texts.items()}
    files[f"{prefix}_vectors.json"] = json_bytes(
        dict(data, spec=spec.name, spec_sha256=spec.source_hash))
    return with_manifest(spec, options, files)
