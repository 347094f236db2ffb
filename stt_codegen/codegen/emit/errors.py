"""Exceptions raised by the code emitter.

Both derive from :class:`stt_codegen.errors.ToolchainError`, so the command line reports
them as one line (``error: ...``) without a traceback, exit code 3.
"""

from __future__ import annotations

from stt_codegen.errors import ToolchainError

__all__ = ["EmitError", "UnsupportedOperation"]


class EmitError(ToolchainError):
    """A CasADi Function cannot be turned into code (not SX, free symbols, bad names...)."""


class UnsupportedOperation(EmitError):
    """The emitter (or one printer) has no translation for a CasADi operation.

    Parameters
    ----------
    op : str
        Name of the operation: the emitter's op name (e.g. ``"erfinv"``) or, for an op
        code unknown to the emitter's table, the CasADi constant name
        (e.g. ``"OP_ERFINV"``) or ``"op code 123"``.
    function : str
        Name of the CasADi Function in which the operation occurs.
    detail : str, optional
        Extra explanation (which printer, which instruction).
    """

    def __init__(self, op: str, function: str, detail: str = "") -> None:
        self.op = op
        self.function = function
        self.detail = detail
        message = f"unsupported operation {op!r} in CasADi Function {function!r}"
        if detail:
            message += f": {detail}"
        super().__init__(message)
