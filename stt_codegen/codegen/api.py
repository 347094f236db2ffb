"""The library's code generation call: design -> standalone controller files in a folder."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from ..spec.loader import Spec
from ..tube.parameters import TubeDesign
from .generate import generate_files
from .options import LANGUAGES, parse_options
from .output import write_generation


def generate(spec: Spec, design: TubeDesign, out_dir: str | Path,
             languages: str | Sequence[str] = LANGUAGES,
             precision: str = "double") -> list[Path]:
    """Write the standalone controller of a designed tube into a folder.

    What ``stt-codegen generate SPEC -o DIR`` writes: for C, ``P.h`` and ``P.c`` (C99,
    ``<math.h>`` only, no allocation), ``P_selftest.c``, a Makefile; for Python, ``P.py``
    (imports only :mod:`math`); the test vectors ``P_vectors.json`` and ``manifest.json``
    (``P`` is the spec name with ``-`` replaced by ``_``). The code computes law (13) with
    the tube of eqs. (2)-(10) and the implicit step of the adaptive law (11).

    Parameters
    ----------
    spec : Spec
        Its name and ``source_hash`` go into the files.
    design : TubeDesign
        From :func:`stt_codegen.design_tube`.
    out_dir : str or path
        Folder; created if missing (its parent must exist). Files of a previous
        generation are replaced; anything else in it is refused. Nothing is half-written.
    languages : str or sequence of str, optional
        Subset of ``("c", "python")``, or the same comma-separated; default both.
    precision : {"double", "single"}, optional
        Floating-point type of the C code (``double`` or ``float``); the Python module
        always computes in Python floats.

    Returns
    -------
    list of pathlib.Path
        The files written, sorted by name.

    Raises
    ------
    SpecError
        Unknown language (field ``languages``) or precision (``precision``); an unusable
        or foreign output folder (``out_dir``).
    ToolchainError
        ``CodegenError`` or ``EmitError``: the model could not be turned into code.
    """
    options = parse_options(languages, precision)
    files = generate_files(spec, design, options)
    write_generation(out_dir, files)
    return [Path(out_dir) / name for name in sorted(files)]
