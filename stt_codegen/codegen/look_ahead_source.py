"""Standalone C and Python of the look-ahead variant for differential-drive bases.

The entry point has the first order's argument order, ``<prefix>_step(x, t, dt, alpha, u,
alpha_next) -> status`` with ``x = (x, y, theta)`` and ``u = (v, omega)``, and its statuses;
it computes :func:`stt_codegen.tube.look_ahead.look_ahead_step` of a design, bit for bit in
double precision.

* C: a variant of the first-order source (:func:`.generate.c_source_context`,
  ``c_source.c.j2``): the same tables and table-driven tube, ``P_tube``, ``P_alpha_step``
  and input checks, with the variant's law (``look_ahead_source.c.j2``: the pieces
  ``look_ahead_point`` and ``base_command`` around the first order's ``law``, its
  ``saturate`` with the base's limits, ``saturate_between`` with a ``reverse_speed``).
* Python: a variant of the first-order module (:func:`.generate.python_module_context`,
  ``python_module.py.j2``) in the same way (``look_ahead_module.py.j2``).

The text is in the Jinja2 templates of the top-level ``templates/``, rendered through
:func:`.render.render` as the other variants' files are; this module only prepares the data.
"""

from __future__ import annotations

import hashlib

import casadi

from ..tube.look_ahead import LookAhead, base_command, look_ahead_point
from ..tube.model import build_model
from ..tube import pieces as P
from ..tube.parameters import Status, TubeDesign
from ..version import __version__
from ..design.output_bound import base_clamp
from ..design.prediction import delay_predictor
from .functions import deployed_functions
from .generate import c_source_context, input_limits, python_module_context, timing_context
from .render import c_real, render
from .tube_data import TubeCapacity, require_capacity, table_names

__all__ = ["look_ahead_c_files", "look_ahead_generation", "look_ahead_python_file",
           "look_ahead_vectors"]


def _check(design: TubeDesign, look_ahead: LookAhead, prefix: str) -> None:
    if not prefix.isidentifier() or not prefix.isascii():
        raise ValueError(f"prefix {prefix!r} is not an identifier")
    if design.dimension != 2 or design.input_bound is not None:
        raise ValueError("the look-ahead variant takes a 2-dimensional tube without an "
                         "input_bound of its own (the base's limits are LookAhead's)")


def _context(design: TubeDesign, look_ahead: LookAhead, prefix: str, precision: str,
             literal, timing: tuple[float, float] = (0.0, 0.0)) -> dict:
    """The banner's fields, the names, the statuses, the input domain's limits, the axle
    offset and the base's limits, printed by ``literal``."""
    limits = input_limits(design)
    digest = hashlib.sha256((repr(design) + repr(look_ahead)).encode()).hexdigest()
    bound = look_ahead.input_bound
    return {"spec_name": design.name, "design_hash": digest,
            "toolkit_version": __version__, "casadi_version": casadi.__version__,
            "precision": precision, "P": prefix, "U": prefix.upper(),
            "statuses": [(s.name, int(s)) for s in Status
                         if s not in (Status.OUTSIDE_VELOCITY_TUBE, Status.INPUT_CLAMPED)
                         or (s == Status.INPUT_CLAMPED and bound is not None)],
            "t_c": literal(design.prescribed_time), "rate_hz": literal(design.rate_hz),
            **timing_context(design.rate_hz, timing, literal),
            **{name: literal(value) for name, value in limits.items()},
            "axle_offset": literal(look_ahead.axle_offset),
            "input_bound": None if bound is None else [literal(b) for b in bound],
            "input_lower": (None if look_ahead.input_lower is None
                            else [literal(b) for b in look_ahead.input_lower]),
            "reverse_speed": (None if look_ahead.reverse_speed is None
                              else literal(look_ahead.reverse_speed)),
            # without limits: what the clamp of the errors allows, in words (3 digits)
            "output_clamp": (None if bound is not None else
                             [f"{c:.3g}" for c in base_clamp(design.gain,
                                                             look_ahead.axle_offset)])}


def _pieces(design: TubeDesign, look_ahead: LookAhead, predictor: casadi.Function | None,
            capacity: TubeCapacity | None) -> list:
    """The CasADi pieces the variant's C and Python compose: the first order's, the error
    transform of the switch (with the tube as data), the look-ahead point, the base's
    command, the clamp (with the base's limits) and the predictor."""
    return [*deployed_functions(build_model(design), capacity is not None),
            *([P.error_transform(design.dimension)] if capacity is not None else []),
            look_ahead_point(), base_command(),
            *([] if look_ahead.input_bound is None else [P.saturate(2)]
              if look_ahead.input_lower is None else [P.saturate_between(2)]),
            *([predictor] if predictor is not None else [])]


def look_ahead_c_files(design: TubeDesign, look_ahead: LookAhead, prefix: str,
                       precision: str = "double", timing: tuple[float, float] = (0.0, 0.0),
                       predictor: casadi.Function | None = None,
                       capacity: TubeCapacity | None = None) -> dict[str, str]:
    """``{<prefix>.h: text, <prefix>.c: text}`` of the look-ahead controller.

    Parameters
    ----------
    design : TubeDesign
        The look-ahead point's tube (2 dimensions, no ``input_bound`` of its own).
    look_ahead : LookAhead
        The axle offset and the base's limits.
    prefix : str
        A C identifier: the file names and the prefix of every public name.
    precision : {"double", "single"}
    timing : (float, float)
        ``(delay, jitter)`` of the spec, s: the header's timing contract.
    predictor : casadi.Function, optional
        With ``[controller] compensate_delay``, the spec's
        :func:`~stt_codegen.design.prediction.delay_predictor`: ``P_predict`` is generated.
    capacity : TubeCapacity, optional
        The tube as data with these capacities (:mod:`.tube_data`; ``P_switch`` tests the
        look-ahead point of the base's state); ``None`` (default): the design's tables.

    Returns
    -------
    dict of str to str
        Deterministic for given arguments, CasADi and toolkit versions.

    Raises
    ------
    ValueError
        ``prefix`` not a C identifier, or a tube the variant does not take.
    SpecError
        The design does not fit ``capacity`` (field ``tube_data``).
    """
    _check(design, look_ahead, prefix)
    if capacity is not None:
        require_capacity(design, capacity)
    single = precision == "single"
    functions = _pieces(design, look_ahead, predictor, capacity)
    context = dict(c_source_context(design, prefix, precision, functions, capacity),
                   **_context(design, look_ahead, prefix, precision,
                              lambda v: c_real(v, single), timing), look_ahead=True,
                   predict=predictor is not None)
    return {name: render(template, filename=name, **context)
            for name, template in ((f"{prefix}.h", "look_ahead_header.h.j2"),
                                   (f"{prefix}.c", "look_ahead_source.c.j2"))}


def look_ahead_python_file(design: TubeDesign, look_ahead: LookAhead,
                           prefix: str, timing: tuple[float, float] = (0.0, 0.0),
                           predictor: casadi.Function | None = None,
                           capacity: TubeCapacity | None = None) -> dict[str, str]:
    """``{<prefix>.py: text}``: ``step(x, t, dt, alpha) -> (u, alpha_next, status)`` with
    ``x = (x, y, theta)``, ``tube`` and ``alpha_step``: the same functions, statuses and
    input checks as the C (imports ``math`` only).

    Parameters
    ----------
    design : TubeDesign
        The look-ahead point's tube.
    look_ahead : LookAhead
    prefix : str
        Module name, an ASCII identifier.
    timing : (float, float)
        ``(delay, jitter)`` of the spec, s: the module's ``DELAY`` and ``JITTER``.
    predictor : casadi.Function, optional
        As :func:`look_ahead_c_files`: ``predict(x, u_held)`` is generated.
    capacity : TubeCapacity, optional
        The tube as data with these capacities (``switch`` tests the look-ahead point of
        the base's state), as :func:`look_ahead_c_files`; ``None`` (default): the design's
        tables.

    Returns
    -------
    dict of str to str
        One entry, ``<prefix>.py`` and its text.

    Raises
    ------
    ValueError
        ``prefix`` not an identifier, or a tube the variant does not take.
    SpecError
        The design does not fit ``capacity`` (field ``tube_data``).
    """
    _check(design, look_ahead, prefix)
    if capacity is not None:
        require_capacity(design, capacity)
    name = f"{prefix}.py"
    literal = lambda v: repr(float(v))  # noqa: E731 - Python floats, printed exactly
    context = {**python_module_context(design, _pieces(design, look_ahead, predictor, capacity),
                                       capacity, timing),
               **_context(design, look_ahead, prefix, "double", literal, timing),
               "look_ahead": True, "predict": predictor is not None}
    return {name: render("look_ahead_module.py.j2", filename=name, **context)}


def look_ahead_vectors(design: TubeDesign, look_ahead: LookAhead, precision: str) -> dict:
    """Test vectors of the look-ahead step from the numpy oracle (JSON-ready, deterministic),
    in the first order's layout (:func:`.vectors.test_vectors`).

    Points: the first order's inputs for the look-ahead point's tube
    (:func:`.vectors.sample_inputs`: inside and outside points with a certain status) taken
    as the point ``p``, a heading ``theta`` from a fixed seed, and the base's state
    ``(p - l (cos theta, sin theta), theta)`` rounded to float32 (exact in both precisions);
    kept where the status is still certain in the precision
    (:func:`.tolerance.look_ahead_bounds`) and, with the base's limits, where the clamp's
    decision is (every ``|u_i|`` farther from its limit than its tolerance plus the
    limit's rounding); then the copies of :func:`.vectors.period_copies` (the law's
    ``OK`` and ``INPUT_CLAMPED`` each at ``dt = PERIOD`` and off it). Expected ``u``,
    ``alpha_next``, the step's status from
    :func:`stt_codegen.tube.look_ahead_reference.look_ahead_status`, the tube from
    :func:`stt_codegen.tube.reference.adaptive_tube`; tolerances ``tol_u``
    (:func:`.tolerance.look_ahead_bounds`), ``tol_alpha_next``, ``tol_gamma`` (the first
    order's), double ones with the floor ``1e-12 max(1, |ref|)``.

    Parameters
    ----------
    design : TubeDesign
        The look-ahead point's tube.
    look_ahead : LookAhead
        The axle offset and the base's limits.
    precision : {"double", "single"}

    Returns
    -------
    dict
        Keys ``x`` (N, 3), ``t``, ``dt``, ``alpha`` (N, 4), ``u`` (N, 2), ``alpha_next``,
        ``status``, ``gamma_L``, ``gamma_U``, ``tol_u``, ``tol_alpha_next``, ``tol_gamma``,
        ``unit_roundoff``.
    """
    import numpy as np

    from ..tube import look_ahead_reference as LR
    from ..tube import reference
    from . import tolerance as T
    from .vectors import period_copies, sample_inputs, vector_document, with_copies

    def f32(a):
        return np.asarray(a, dtype=np.float32).astype(np.float64)

    p = sample_inputs(design, precision)
    t, dt, alpha = p["t"], p["dt"], p["alpha"]
    offset = look_ahead.axle_offset
    theta = f32(np.random.default_rng(23).uniform(-np.pi, np.pi, t.size))
    states = np.column_stack([f32(p["x"][:, 0] - offset * np.cos(theta)),
                              f32(p["x"][:, 1] - offset * np.sin(theta)), theta])
    unit = T.unit_roundoff(precision)
    u_point = reference.law_step(design, LR.point(states, offset), t, dt, alpha)[0]
    u_free = LR.command(states, u_point, offset)
    tol_u, keep = T.look_ahead_bounds(design, offset, states, t, alpha, u_point, u_free, unit)
    if look_ahead.input_bound is not None:
        bound = np.asarray(look_ahead.input_bound, dtype=float)
        lower = -bound if look_ahead.input_lower is None else np.asarray(look_ahead.input_lower)
        for end in (bound, lower):           # away from either end of the clamp
            keep &= np.all(np.abs(u_free - end) > tol_u + 2.0 * unit * bound, axis=1)
    kept = {"x": states, "t": t, "dt": dt, "alpha": alpha, "tol_u": tol_u}
    kept = {k: v[keep] for k, v in kept.items()}
    # the law's status does not depend on dt: the step's at dt = PERIOD
    law = LR.look_ahead_status(design, offset, look_ahead.input_bound, kept["x"], kept["t"],
                               np.full(kept["t"].shape, 1.0 / design.rate_hz), kept["alpha"],
                               look_ahead.reverse_speed)[2]
    kept = with_copies(kept, *period_copies(kept["dt"], law, design.rate_hz))
    states, t, dt, alpha, tol_u = (kept[k] for k in ("x", "t", "dt", "alpha", "tol_u"))
    u, alpha_next, status = LR.look_ahead_status(design, offset, look_ahead.input_bound,
                                                 states, t, dt, alpha, look_ahead.reverse_speed)
    return vector_document(design, precision, states, t, dt, alpha, u, alpha_next, status,
                           tol_u)


def look_ahead_generation(design, options) -> dict[str, bytes]:
    """Every file of the look-ahead controller of a differential-drive design, in memory.

    The file set of every variant (:mod:`.fileset`), ``P`` the spec's C name: ``P.h``,
    ``P.c``, ``P_selftest.c`` (the vectors replayed through ``P_step``, ``P_alpha_step``
    and ``P_tube``), ``Makefile`` and ``CMakeLists.txt`` (with ``"c"`` in
    ``options.langs``, in ``options.precision``), ``P.py`` (with ``"python"``),
    ``P_vectors.json`` (:func:`look_ahead_vectors`) and ``manifest.json``.

    Parameters
    ----------
    design : Design
        Of a spec with ``plant.model = "differential-drive"``.
    options : Options

    Returns
    -------
    dict of str to bytes

    Raises
    ------
    SpecError
        Not a differential-drive spec (field ``plant.model``).
    """
    from .fileset import (build_files, file_context, selftest_file, vector_tables,
                          vectors_file, with_manifest)

    look_ahead = design.look_ahead
    spec = design.spec
    predictor = delay_predictor(spec, design.tube, look_ahead)
    context = dict(file_context(spec, options.precision), no_control=True)
    prefix = context["P"]
    if options.tube_data is not None:         # the self-test runs the design's tube as data
        context["T"] = table_names(prefix, True)
    vectors = look_ahead_vectors(design.tube, look_ahead, options.precision)
    texts: dict[str, str] = {}
    if "c" in options.langs:
        texts.update(look_ahead_c_files(design.tube, look_ahead, prefix, options.precision,
                                        (spec.delay, spec.jitter), predictor,
                                        options.tube_data))
        texts.update(build_files(context))
        texts.update(selftest_file(context, vectors, vector_tables(vectors), options.precision))
    if "python" in options.langs:
        texts.update(look_ahead_python_file(design.tube, look_ahead, prefix,
                                            (spec.delay, spec.jitter), predictor,
                                            options.tube_data))
    files = {name: text.encode() for name, text in texts.items()}
    files[f"{prefix}_vectors.json"] = vectors_file(
        spec, options.precision, vectors,
        "the numpy reference (stt_codegen.tube.look_ahead_reference)")
    return with_manifest(spec, options, files)
