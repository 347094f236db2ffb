"""The file set every controller variant writes: build files, self-test, vectors, manifest.

Every generation (the first order's :func:`.generate.generate_files`, the cascade's
:func:`.cascade_source.cascade_generation`, the look-ahead variant's
:func:`.look_ahead_source.look_ahead_generation`) writes, with ``P`` the spec's C name,
``P.h P.c P_selftest.c Makefile CMakeLists.txt`` (``"c"`` in the languages), ``P.py``
(``"python"``), ``P_vectors.json`` and ``manifest.json``. The variants differ only in the
text of ``P.h``, ``P.c``, ``P.py`` and the vectors; the build files come from one pair of
templates (``Makefile.j2``, ``CMakeLists.txt.j2``), the self-test from ``c_selftest.c.j2``
(the cascade's extends it: ``cascade_selftest.c.j2``), the manifest from
:func:`.generate.manifest`, all through this module.
"""

from __future__ import annotations

import hashlib
import json

import casadi
import numpy as np

from ..version import __version__
from . import tolerance
from .render import c_real, render

__all__ = ["BUILD_TEMPLATES", "GENERATOR", "MANIFEST", "TOLERANCE_DOC", "build_files",
           "c_literal_rows", "file_context", "json_bytes", "manifest", "selftest_file",
           "vector_tables", "vectors_file", "with_manifest"]

MANIFEST = "manifest.json"
GENERATOR = "stt-codegen"

#: The build files and their templates, the same for every variant.
BUILD_TEMPLATES = (("Makefile", "Makefile.j2"), ("CMakeLists.txt", "CMakeLists.txt.j2"))

#: What the vectors' tolerances are, per precision (the vectors file and the self-test say it).
TOLERANCE_DOC = {
    "double": ("max(1e-12 max(1, |ref|), B) with B the first-order rounding bound of "
               "stt_codegen.codegen.tolerance at unit roundoff 2^-53 (covers a libm a few ulp "
               "from glibc's on ill-conditioned points near the tube boundary)."),
    "single": ("B, the rounding bound of stt_codegen.codegen.tolerance at unit roundoff 2^-24: "
               "tube bounds 64 u S (S = 1 + max |state bound| + max |alpha|); u: the exact "
               "spread of the law over the error of e; alpha_next 64 u (S + |alpha| + "
               "|alpha_next|)."),
}


def json_bytes(data: dict) -> bytes:
    """``data`` as the generated JSON files hold it: sorted keys, indent 1, ASCII, a final
    newline, no NaN.

    Parameters
    ----------
    data : dict
        JSON-ready.

    Returns
    -------
    bytes
    """
    return (json.dumps(data, indent=1, sort_keys=True, allow_nan=False) + "\n").encode("ascii")


def c_literal_rows(rows, single: bool) -> list[list[str]]:
    """C literals of a table of numbers, in the precision (``float`` literals: the shortest
    decimal of the float32 number, with an ``f``).

    Parameters
    ----------
    rows : sequence of sequences of float
    single : bool
        Single precision.

    Returns
    -------
    list of list of str
    """
    if single:
        return [[np.format_float_scientific(np.float32(v), unique=True, trim="0") + "f"
                 for v in row] for row in rows]
    return [[c_real(v, False) for v in row] for row in rows]


def file_context(spec, precision: str) -> dict:
    """The variables the build files and the self-test of a variant take beyond its own:
    the names (``P`` the spec's C name, ``U`` in capitals), the banner's fields, the real
    type, and ``wide_state`` (x and u have their own lengths, ``P_N_STATE`` and
    ``P_N_INPUT``).

    Parameters
    ----------
    spec : Spec
        The spec generated from.
    precision : {"double", "single"}

    Returns
    -------
    dict
    """
    prefix = spec.c_name
    return {"P": prefix, "U": prefix.upper(), "spec_name": spec.name,
            "spec_hash": spec.source_hash, "toolkit_version": __version__,
            "casadi_version": casadi.__version__, "precision": precision,
            "real": "float" if precision == "single" else "double", "wide_state": True}


def build_files(context: dict) -> dict[str, str]:
    """``Makefile`` and ``CMakeLists.txt`` of a generation (``make selftest`` builds
    ``P.c`` and ``P_selftest.c`` and runs the self-test).

    Parameters
    ----------
    context : dict
        Template variables: ``P``, ``U``, ``spec_name``, ``spec_hash``, ``precision``,
        ``toolkit_version``, ``casadi_version``.

    Returns
    -------
    dict of str to str
    """
    return {name: render(template, filename=name, **context)
            for name, template in BUILD_TEMPLATES}


def selftest_file(context: dict, inputs: dict, expected: list[tuple[str, list, int]],
                  precision: str, template: str = "c_selftest.c.j2") -> dict[str, str]:
    """``{P_selftest.c: text}``: the vectors compiled in, every API function checked on them.

    Parameters
    ----------
    context : dict
        The C templates' variables (``P``, ``U``, the banner's fields, ``real``).
    inputs : dict
        ``x`` (N, N_STATE), ``t`` (N,), ``dt`` (N,), ``alpha`` (N, N_ALPHA) and ``status``
        (N,): the vectors' inputs (exact in the precision) and the step's expected
        statuses; with ``control_status`` (N,), ``P_control``'s (a variant with
        ``P_control``: the law's status, no ``OFF_PERIOD``).
    expected : list of (str, list of list of float, int)
        The tables of expected values and tolerances (``EXP_U``, ``TOL_U``, ...): name, rows,
        width; kept in double.
    precision : {"double", "single"}
    template : str, optional
        The self-test template: ``c_selftest.c.j2`` or one extending it.

    Returns
    -------
    dict of str to str
    """
    single = precision == "single"
    name = f"{context['P']}_selftest.c"
    tables = [(table, c_literal_rows(rows, False), width) for table, rows, width in expected]
    return {name: render(
        template, filename=name, **context, count=len(inputs["t"]),
        x=c_literal_rows(inputs["x"], single), alpha=c_literal_rows(inputs["alpha"], single),
        t=c_literal_rows([inputs["t"]], single)[0], dt=c_literal_rows([inputs["dt"]], single)[0],
        status=inputs["status"], control_status=inputs.get("control_status"), tables=tables,
        tolerance_doc=TOLERANCE_DOC[precision])}


def vector_tables(vectors: dict) -> list[tuple[str, list, int]]:
    """The self-test's tables of vectors in the first order's layout
    (:func:`.vectors.test_vectors`; the look-ahead variant's too): ``EXP_U``,
    ``EXP_ALPHA_NEXT``, ``EXP_GAMMA_L``, ``EXP_GAMMA_U``, ``TOL_U``, ``TOL_ALPHA_NEXT``,
    ``TOL_GAMMA``.

    Parameters
    ----------
    vectors : dict
        Keys ``u``, ``alpha_next``, ``gamma_L``, ``gamma_U``, ``tol_u``,
        ``tol_alpha_next``, ``tol_gamma`` (rows of numbers).

    Returns
    -------
    list of (str, list of list of float, int)
        Name, rows, width: the ``expected`` of :func:`selftest_file`.
    """
    tables = [(f"EXP_{k.upper()}", vectors[k], len(vectors[k][0]))
              for k in ("u", "alpha_next", "gamma_L", "gamma_U")]
    return tables + [(f"TOL_{k[4:].upper()}", vectors[k], len(vectors[k][0]))
                     for k in ("tol_u", "tol_alpha_next", "tol_gamma")]


def vectors_file(spec, precision: str, vectors: dict, source: str) -> bytes:
    """``P_vectors.json`` in the first order's layout: the vectors with the spec's name and
    hash, the precision and what the tolerances are.

    Parameters
    ----------
    spec : Spec
        The spec generated from.
    precision : {"double", "single"}
    vectors : dict
        JSON-ready vectors (:func:`.vectors.test_vectors`).
    source : str
        What computed the expected values (named in the ``_generated`` line).

    Returns
    -------
    bytes
    """
    return json_bytes({
        "_generated": f"GENERATED FILE, DO NOT EDIT: test vectors of spec {spec.name!r} "
                      f"from {source}.",
        "spec": spec.name, "spec_sha256": spec.source_hash, "precision": precision,
        "tolerance": TOLERANCE_DOC[precision], **vectors})


def with_manifest(spec, options, files: dict[str, bytes]) -> dict[str, bytes]:
    """The files with ``manifest.json`` added, sorted by name.

    Parameters
    ----------
    spec : Spec
        The spec generated from (its name and source hash).
    options : Options
        The generation's languages and precision.
    files : dict of str to bytes
        Every other file of the generation.

    Returns
    -------
    dict of str to bytes
    """
    out = dict(files)
    out[MANIFEST] = json_bytes(manifest(spec, options, files))
    return dict(sorted(out.items()))


def manifest(spec: Spec, options: Options, files: dict[str, bytes]) -> dict:
    """The manifest: versions, spec hash, options and the SHA-256 of every other file.

    Parameters
    ----------
    spec : Spec
        The spec generated from (its name and source hash).
    options : Options
        The generation's languages and precision.
    files : dict of str to bytes
        The generated files by name; the manifest's own entry is skipped.

    Returns
    -------
    dict
        JSON-ready; file hashes as hex SHA-256, in name order.
    """
    return {
        "_generated": "GENERATED FILE, DO NOT EDIT: manifest of an stt-codegen generation.",
        "generator": GENERATOR,
        "toolkit_version": __version__,
        "casadi_version": casadi.__version__,
        "spec": {"name": spec.name, "sha256": spec.source_hash},
        "options": options.to_json(),
        "files": {name: hashlib.sha256(data).hexdigest() for name, data in sorted(files.items()) if name != MANIFEST},
        "tolerance_unit_roundoff": tolerance.unit_roundoff(options.precision),
    }
