"""Code generation: standalone C99 and Python controllers of a designed tube.

* :func:`~.generate.generate_files` - every file of one generation, in memory;
* :func:`~.output.write_generation` - write them safely into ``-o DIR``;
* :mod:`.bundled` - the committed ``generated/`` folder and its drift check;
* :class:`~.controllers.CController`, :class:`~.controllers.GeneratedPythonController` -
  the generated code as backends ``c`` and ``python``;
* :mod:`.cli` - the ``generate`` and ``check`` subcommands' arguments.
"""

from .generate import generate_files
from .options import Options, parse_options
from .output import write_generation

__all__ = ["Options", "generate_files", "parse_options", "write_generation"]
