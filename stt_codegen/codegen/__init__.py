"""Code generation: standalone C99 and Python controllers of a designed tube.

* :func:`~.generate.generate_files` - every file of one generation, in memory;
* :func:`~.output.write_generation` - write them safely into ``-o DIR``;
* :func:`~.api.generate` - both, for a :class:`~stt_codegen.design.result.Design` (the
  front door's ``stt_codegen.generate``);
* :mod:`.bundled` - the committed ``generated/`` folder and its drift check.

The generated code runs as the backends ``c`` and ``python`` in
:mod:`stt_codegen.runtime.compiled`.
"""

from .generate import generate_files
from .options import Options, parse_options
from .output import write_generation

__all__ = ["Options", "generate_files", "parse_options", "write_generation"]
