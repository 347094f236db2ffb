"""Errors of the code generator (all :class:`~stt_codegen.errors.ToolchainError`: exit code 3)."""

from __future__ import annotations

from ..errors import ToolchainError

__all__ = ["CodegenError"]


class CodegenError(ToolchainError):
    """Generation cannot proceed: unexpected CasADi output, a failed build, an unsafe output folder."""
