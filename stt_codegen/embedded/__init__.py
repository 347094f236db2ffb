"""Embedded harness: build bare-metal Cortex-M4F programs, run them under QEMU, measure.

Public API: :func:`build_elf`, :func:`run_qemu`, :func:`measure`, the result
types :class:`BuildResult`, :class:`RunResult`, :class:`Footprint`, and
:class:`MissingTool` (a tool is not installed; names its Debian package);
:func:`run_embedded` (the ``embedded`` subcommand's pipeline; its arguments are in
:mod:`stt_codegen.cli.embedded`).
"""

from stt_codegen.embedded.footprint import Footprint, measure
from stt_codegen.embedded.target import (BuildError, BuildResult, RunError, RunResult,
                                         build_elf, run_qemu)
from stt_codegen.embedded.toolchain import (MissingTool, find_toolchain, missing_message,
                                            missing_tools)

from stt_codegen.embedded.deploy import run_embedded

__all__ = ["BuildError", "BuildResult", "Footprint", "MissingTool", "RunError", "RunResult",
           "build_elf", "find_toolchain", "measure", "missing_message", "missing_tools",
           "run_embedded", "run_qemu"]
