"""The library's code generation call: a design -> standalone controller files in a folder."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from ..design.result import Design, require_design
from ..spec.variants import variant_of
from .options import LANGUAGES, Options, parse_options
from .tube_data import TubeCapacity, require_tube_data
from .output import write_generation

__all__ = ["design_files", "generate"]


def design_files(design: Design, options: Options) -> dict[str, bytes]:
    """The generated files of a design, in memory: the controller of the spec's order.

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`.
    options : Options
        Languages and precision (:func:`~.options.parse_options`).

    Returns
    -------
    dict of str to bytes
        File name to content, by the spec's variant (role ``generation``): law (13)'s
        controller (:func:`~.generate.first_order_generation`) for a first-order plant, the cascade
        controller (:func:`~.cascade_source.cascade_generation`, docs/second-order.md)
        for a second-order one, the look-ahead controller
        (:func:`~.look_ahead_source.look_ahead_generation`, docs/differential-drive.md)
        for a differential-drive base.

    Raises
    ------
    SpecError
        ``options.tube_data`` for a variant whose C does not take its tube as data (field
        ``tube_data``).
    """
    if options.tube_data is not None:
        require_tube_data(design.spec, tuple(options.langs))
    return variant_of(design.spec).entry("generation")(design, options)


def generate(design: Design, out_dir: str | Path,
             languages: str | Sequence[str] = LANGUAGES,
             precision: str = "double",
             tube_data: bool | TubeCapacity = False) -> list[Path]:
    """Write the standalone controller of a designed tube into a folder.

    What ``stt-codegen generate SPEC -o DIR`` writes: for C, ``P.h`` and ``P.c`` (C99,
    ``<math.h>`` only, no allocation), ``P_selftest.c``, a Makefile and a CMakeLists.txt;
    for Python, ``P.py`` (imports only :mod:`math`); the test vectors ``P_vectors.json``
    and ``manifest.json`` (``P`` is the spec name with ``-`` replaced by ``_``). The code
    computes law (13), ``u = -k xi(x, t) epsilon(x, t)``, with the tube of eqs. (2)-(10)
    and the implicit step of the adaptive law (11). For a second-order ``plant.model``:
    the cascade controller instead (:func:`~.cascade_source.cascade_generation`,
    docs/second-order.md).

    Parameters
    ----------
    design : Design
        From :func:`stt_codegen.design_tube`; its spec's name and ``source_hash`` go into
        the files, its tube's numbers into the code.
    out_dir : str or path
        Folder; created if missing (its parent must exist). Files of a previous
        generation are replaced; anything else in it is refused. Nothing is half-written.
    languages : str or sequence of str, optional
        Subset of ``("c", "python")`` (a list, a tuple, a numpy array of strings), or
        the same comma-separated; default both.
    precision : {"double", "single"}, optional
        Floating-point type of the C code (``double`` or ``float``); the Python module
        always computes in Python floats.
    tube_data : bool or TubeCapacity, optional
        Code whose tube is data (``True``: 8 segments and 32 windows): every function
        takes a ``P_tube_data`` (Python: a ``TubeData``), ``P_switch`` (``switch``)
        replaces the active tube at run time where the state lies in the new one
        (docs/sensing.md, "The tube as data"); C and Python, law (13)'s controller only.
        Default ``False``: the tube in tables.

    Returns
    -------
    list of pathlib.Path
        The files written, sorted by name.

    Raises
    ------
    TypeError
        ``design`` is not a :class:`~stt_codegen.design.result.Design` (a ``TubeDesign``
        or a ``Spec``, say): call :func:`stt_codegen.design_tube` first.
    SpecError
        Unknown language (field ``languages``) or precision (``precision``); an unusable
        or foreign output folder (``out_dir``); the tube as data for another variant, or
        smaller than the spec's tube (``tube_data``).
    ToolchainError
        ``CodegenError`` or ``EmitError``: the model could not be turned into code.

    See Also
    --------
    stt_codegen.design_tube : the design to generate code for.
    stt_codegen.simulate : run the generated C or Python in closed loop (``backend="c"``,
        ``"python"``).
    stt_codegen.codegen.generate.generate_files : the same files in memory.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> files = stt.generate(design, "s1-float", languages=["c"], precision="single")
    >>> [f.name for f in files]                                  # doctest: +NORMALIZE_WHITESPACE
    ['CMakeLists.txt', 'Makefile', 'manifest.json', 'omnirobot_s1.c', 'omnirobot_s1.h',
     'omnirobot_s1_selftest.c', 'omnirobot_s1_vectors.json']
    """
    design = require_design(design, "generate")
    options = parse_options(languages, precision, tube_data or None)
    files = design_files(design, options)
    write_generation(out_dir, files)
    return [Path(out_dir) / name for name in sorted(files)]
