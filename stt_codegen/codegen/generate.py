"""All generated files for one spec, as ``{relative name: bytes}`` (nothing is written here).

:func:`generate_files` is pure: the same spec, design, options, CasADi and toolkit
versions give the same bytes (no timestamps, no paths, no set iteration). Files, with
``P`` the spec's C name:

* C (``--lang c``): ``P.h`` (the API only), ``P.c`` (typed API + bodies printed by
  :class:`~stt_codegen.codegen.emit.CPrinter`), ``P_selftest.c`` (the vectors embedded),
  ``Makefile`` and ``CMakeLists.txt``;
* Python (``--lang python``): ``P.py`` (always double: Python floats);
* always: ``P_vectors.json`` (inputs, reference outputs, tolerances of the precision)
  and ``manifest.json`` (:data:`MANIFEST`).
"""

from __future__ import annotations

import dataclasses
import math

import casadi

from ..version import __version__
from .emit import CPrinter, lower, python_source
from ..tube.model import build_model
from ..spec.loader import Spec
from ..design.prediction import delay_predictor
from ..design.search import MAX_INITIAL_ERROR
from ..tube.parameters import NEWTON_ITERATIONS, PERIOD_TOLERANCE, TubeDesign
from . import tolerance
from .functions import deployed_functions
from .fileset import (GENERATOR, MANIFEST, build_files, manifest, selftest_file,
                      vector_tables, vectors_file, with_manifest)
from .options import Options
from .render import c_identifier, c_real, render
from .tables import design_table_rows
from .tube_data import (TubeCapacity, profile_codes, python_names, require_capacity,
                        table_names, table_shape)
from ..tube.pieces import error_transform
from .vectors import test_vectors

__all__ = ["GENERATOR", "MANIFEST", "Options", "c_source_context", "first_order_generation",
           "generate_files", "input_limits", "manifest", "python_module_context",
           "timing_context"]


def generate_files(spec: Spec, design: TubeDesign, options: Options) -> dict[str, bytes]:
    """Every file of one generation, keyed by file name (sorted).

    Parameters
    ----------
    spec : Spec
        Its name (validated) and ``source_hash`` are used.
    design : TubeDesign
        From :func:`stt_codegen.design.search.design_tube`.
    options : Options

    Returns
    -------
    dict of str to bytes

    Raises
    ------
    SpecError
        The spec's C name is not a usable identifier.
    UnsupportedOperation
        The model uses an operation the printers cannot translate.
    """
    prefix = c_identifier(spec.c_name)
    single = options.precision == "single"
    predictor = delay_predictor(spec, design, None)
    capacity = options.tube_data
    if capacity is not None:
        require_capacity(design, capacity)
    functions = [*deployed_functions(build_model(design), capacity is not None),
                 *([error_transform(design.dimension)] if capacity is not None else []),
                 *([predictor] if predictor is not None else [])]
    common = {
        "spec_name": spec.name, "spec_hash": spec.source_hash, "casadi_version": casadi.__version__,
        "toolkit_version": __version__, "precision": options.precision, "P": prefix,
        "U": prefix.upper(), "n": design.dimension, "newton": NEWTON_ITERATIONS,
        "real": "float" if single else "double", "predict": predictor is not None,
    }
    files: dict[str, str] = {}
    vectors = test_vectors(design, options.precision)
    if "c" in options.langs:
        c_ctx = dict(common, **c_source_context(design, prefix, options.precision, functions,
                                                capacity),
                     **timing_context(design.rate_hz, (spec.delay, spec.jitter),
                                      lambda v: c_real(v, single)))
        for name, template in ((f"{prefix}.h", "c_header.h.j2"), (f"{prefix}.c", "c_source.c.j2")):
            files[name] = render(template, filename=name, **c_ctx)
        files.update(build_files(c_ctx))
        files.update(selftest_file(c_ctx, vectors, vector_tables(vectors), options.precision))
    if "python" in options.langs:
        name = f"{prefix}.py"
        files[name] = render("python_module.py.j2", filename=name, **{
            **common, **python_module_context(design, functions, capacity,
                                              (spec.delay, spec.jitter))})
    files_bytes = {k: v.encode("ascii") for k, v in files.items()}
    files_bytes[f"{prefix}_vectors.json"] = vectors_file(
        spec, options.precision, vectors, f"the numpy reference (stt-codegen {__version__})")
    return with_manifest(spec, options, files_bytes)


def first_order_generation(design, options: Options) -> dict[str, bytes]:
    """Every file of law (13)'s controller of a first-order design, in memory: the
    generation entry point of the first order, with the cascade's and the look-ahead
    variant's signature (``(design, options) -> files``).

    Parameters
    ----------
    design : Design
        Of a spec with a first-order ``plant.model``.
    options : Options

    Returns
    -------
    dict of str to bytes
        :func:`generate_files` of the design's spec and tube.
    """
    return generate_files(design.spec, design.tube, options)


def python_module_context(design: TubeDesign, functions: list,
                          capacity: TubeCapacity | None = None,
                          timing: tuple[float, float] = (0.0, 0.0)) -> dict:
    """The variables of ``templates/python_module.py.j2`` that depend on the design: its
    tables (or the tube as data), the ``body_*`` functions printed from ``functions``, the
    timing contract and the input domain's limits (the first order's module, and the
    look-ahead variant's, which extends it).

    Parameters
    ----------
    design : TubeDesign
        The tube the module runs (for the look-ahead variant, its point's).
    functions : list of casadi.Function
        The pieces the module composes, each printed as ``body_<name>``.
    capacity : TubeCapacity, optional
        The tube as data with these capacities; ``None``: the design's tables.
    timing : (float, float)
        ``(delay, jitter)`` of the spec, s.

    Returns
    -------
    dict
    """
    limits = input_limits(design)
    programs = [dataclasses.replace(lower(f), name=f"body_{f.name()}") for f in functions]
    tables = design_table_rows(design, lambda v: repr(float(v)), False)
    return dict(T=python_names(capacity is not None), capacity=capacity,
                blended=table_shape(tables, capacity).blended,
                newton=NEWTON_ITERATIONS, max_initial_error=repr(float(MAX_INITIAL_ERROR)),
                bodies=python_source(programs).rstrip("\n"),
                spec_tables=tables,
                profile_codes=profile_codes(capacity),
                t_c=repr(float(design.prescribed_time)), rate_hz=repr(float(design.rate_hz)),
                **timing_context(design.rate_hz, timing, lambda v: repr(float(v))),
                dt_min=repr(limits["dt_min"]), dt_max=repr(limits["dt_max"]),
                alpha_max=repr(limits["alpha_max"]),
                input_bound=(None if design.input_bound is None else
                             [repr(float(b)) for b in design.input_bound]))


def c_source_context(design: TubeDesign, prefix: str, precision: str,
                     functions: list, capacity: TubeCapacity | None = None) -> dict:
    """The variables of ``templates/c_source.c.j2`` and ``c_header.h.j2`` that depend on the
    design: the printed bodies, the tables, the input domain, the actuator bound.

    Parameters
    ----------
    design : TubeDesign
        The tube (tables, limits, ``input_bound``).
    prefix : str
        The C prefix (a validated identifier).
    precision : {"double", "single"}
    functions : list of casadi.Function
        The pieces whose bodies are printed (``body_<name>``), in order.
    capacity : TubeCapacity, optional
        The tube as data with these capacities (:mod:`.tube_data`); ``None`` (default): the
        design's tube in ``const`` tables.

    Returns
    -------
    dict
        Template variables.
    """
    single = precision == "single"
    limits = input_limits(design)
    bodies = CPrinter(precision, real=f"{prefix}_real", prefix="body_")
    tables = design_table_rows(design, lambda v: c_real(v, single), single)
    return dict(P=prefix, U=prefix.upper(), n=design.dimension, newton=NEWTON_ITERATIONS,
                newton_stop=c_real(tolerance.NEWTON_STOP_SINGLE, True) if single else None,
                real="float" if single else "double", precision=precision,
                bodies=bodies.doprint(functions).rstrip("\n"),
                spec_tables=tables, T=table_names(prefix, capacity is not None),
                max_initial_error=c_real(MAX_INITIAL_ERROR, single),
                shape=table_shape(tables, capacity), capacity=capacity,
                profile_codes=profile_codes(capacity),
                guard=f"{prefix.upper()}_H", zero=c_real(0.0, single),
                period_tolerance=c_real(PERIOD_TOLERANCE, single),
                t_c=c_real(design.prescribed_time, single),
                rate_hz=c_real(design.rate_hz, single),
                dt_min=c_real(limits["dt_min"], single),
                dt_max=c_real(limits["dt_max"], single),
                alpha_max=c_real(limits["alpha_max"], single),
                input_bound=(None if design.input_bound is None else
                             [c_real(b, single) for b in design.input_bound]))


def timing_context(rate_hz: float, timing: tuple[float, float], literal) -> dict[str, str]:
    """The timing contract's numbers, printed by ``literal``: ``period`` (``1 / rate_hz``),
    ``delay`` and ``jitter`` (``[controller] delay`` and ``jitter``, s), the header's
    ``PERIOD``, ``DELAY``, ``JITTER`` (``templates/_c_timing.h.j2``).

    Parameters
    ----------
    rate_hz : float
        The design's rate, Hz.
    timing : (float, float)
        ``(delay, jitter)``, s.
    literal : callable
        A float to its text in the target language.

    Returns
    -------
    dict of str to str
    """
    return {"period": literal(1.0 / rate_hz), "delay": literal(timing[0]),
            "jitter": literal(timing[1])}


def input_limits(design: TubeDesign) -> dict[str, float]:
    """Upper ends of the generated API's input domain (powers of two: exact in float32).

    ``dt_min = 2^-20`` s (about 1 MHz): with a shorter step the Newton start's offset
    ``delta ~ (dt theta)^(1/3)`` from the singularity ``psi + alpha = 0`` can fall below
    one ulp of ``psi`` in single precision, and the step divides 0 by 0.
    ``dt_max``: the smallest power of two ``>= t_c`` (a step longer than the task is a
    usage error). ``alpha_max``: a power of two ``>= 1e6 (1 + max |state bound|)``; the
    adaptive law keeps ``alpha`` below about the state space's extent, and below this
    bound every intermediate of the step stays finite in single precision for specs
    within the loader's 1e12 limit (kappa alpha and (psi + alpha)^2 stay below 1e37).

    Parameters
    ----------
    design : TubeDesign
        The tube (prescribed time and state-space bounds).

    Returns
    -------
    dict of str to float
        ``dt_min`` and ``dt_max`` (s) and ``alpha_max`` (state units).
    """
    scale = 1.0 + max(abs(v) for v in (*design.state_lower, *design.state_upper))
    return {"dt_min": 2.0 ** -20, "dt_max": 2.0 ** math.ceil(math.log2(design.prescribed_time)),
            "alpha_max": 2.0 ** math.ceil(math.log2(1e6 * scale))}
