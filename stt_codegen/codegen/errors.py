"""Errors of the code generator (all :class:`~stt_codegen.errors.SttError`: exit code 2)."""

from __future__ import annotations

from ..errors import SttError


class CodegenError(SttError):
    """Generation cannot proceed: unexpected CasADi output, a failed build, an unsafe output folder."""
