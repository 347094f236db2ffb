"""The toolkit's own exceptions, in three kinds.

Every error the toolkit raises on purpose is an :class:`SttError` of one of three kinds.
The command line turns each into one line ``error: ...`` on standard error, without a
traceback, and an exit code that says which kind it was:

======================  ===========  =====================================================
kind                    exit code    meaning
======================  ===========  =====================================================
:class:`SpecError`      2            bad input: a spec field, a command-line argument, an
                                     output folder; the message names the field
:class:`DesignError`    1            a negative outcome for a valid input: no tube can be
                                     designed, or a check failed
:class:`ToolchainError` 3            a tool (compiler, QEMU, valgrind) is missing or
                                     failed, or the toolkit hit an internal limit
======================  ===========  =====================================================

The mapping lives in one place, :data:`stt_codegen.cli.EXIT_CODES`. Library code speaks in
the user's terms (spec fields and function parameters such as ``"horizon"``), never in
command-line flags: the command line translates a parameter name into its flag.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any


class SttError(Exception):
    """Base class of every error the toolkit raises on purpose.

    Raise one of the three kinds below; a bare :class:`SttError` is treated as a
    :class:`ToolchainError` (an internal failure) by the command line.

    Examples
    --------
    Catch every error the toolkit raises on purpose, whatever its kind:

    >>> import stt_codegen as stt
    >>> try:
    ...     stt.load_spec("no-such-case")
    ... except stt.SttError as error:
    ...     print(type(error).__name__)
    SpecError
    """


class SpecError(SttError, ValueError):
    """Bad input: a spec field (or a value derived from it, or an argument) is invalid.

    Command line: exit code 2.

    Parameters
    ----------
    field : str
        Dotted name of the offending field, e.g. ``"initial.state"`` or
        ``"obstacles[2].lower"``, or the name of a function parameter (``"horizon"``);
        ``""`` for the file as a whole.
    reason : str
        Why the value is rejected, in words.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> doc = {"name": "corridor", "prescribed_time": -5.0,
    ...        "state_space": {"lower": [0.0, 0.0], "upper": [4.0, 1.0]},
    ...        "initial": {"lower": [0.0, 0.0], "upper": [0.5, 1.0]},
    ...        "target": {"lower": [3.5, 0.0], "upper": [4.0, 1.0]}}
    >>> try:
    ...     stt.Spec.from_dict(doc)
    ... except stt.SpecError as error:
    ...     print(error.field, "|", error.reason)
    prescribed_time | must be positive, got -5.0
    """

    def __init__(self, field: str, reason: str) -> None:
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}" if field else reason)


class DesignError(SttError):
    """No spatiotemporal tube satisfying the checks can be designed for a valid spec.

    A negative outcome, not bad input: the spec is well formed, but the design search
    (with its continuous-time certificate) finds no acceptable tube. Command line: exit
    code 1.

    Parameters
    ----------
    message : str
        The reason, in the user's terms.
    kind : enum member, optional
        What failed, as a value of the design package's failure enum (callers branch on
        this, never on the message text); ``None`` where no design was attempted.
    tried : object, optional
        The best rejected tube (a ``TubeDesign``), for a plot of what was tried; ``None``
        where no tube was built.
    advice : mapping of str to float, optional
        What the message names as certified, by spec field (``{"controller.rate_hz":
        230.0}``): each value was designed and certified with the rest of the spec
        unchanged, so a program can follow it; except ``prescribed_time`` given together
        with ``tasks.window_end``, certified with the ``[[tasks]]`` windows that end at
        the spec's ``prescribed_time`` ending at it too
        (:func:`stt_codegen.spec.deadline.with_deadline`). Empty when nothing is named.

    Examples
    --------
    A corridor crossed in 10 ms: no tube moves that fast at 1 kHz. The kind says why
    (:class:`~stt_codegen.design.failures.FailureKind`), the message how to change the spec:

    >>> import stt_codegen as stt
    >>> doc = {"name": "rushed", "prescribed_time": 0.01,
    ...        "state_space": {"lower": [0.0, 0.0], "upper": [4.0, 1.0]},
    ...        "initial": {"lower": [0.0, 0.0], "upper": [0.5, 1.0]},
    ...        "target": {"lower": [3.5, 0.0], "upper": [4.0, 1.0]}}
    >>> try:
    ...     stt.design_tube(stt.Spec.from_dict(doc))
    ... except stt.DesignError as error:
    ...     print(error.kind.name, "|", "controller.rate_hz" in str(error))
    SAMPLING_RATE | True
    """

    def __init__(self, message: str, *, kind: Any = None, tried: Any = None,
                 advice: Mapping[str, float] | None = None) -> None:
        self.kind = kind
        self.tried = tried
        self.advice = dict(advice or {})
        super().__init__(message)


class ToolchainError(SttError):
    """A tool the toolkit drives is missing or failed, or an internal step failed.

    The C compiler, the Cortex-M cross toolchain, QEMU, valgrind, or the code generator
    meeting output it does not expect. Neither the spec's fault nor a negative outcome.
    Command line: exit code 3. Subclasses: ``CodegenError``, ``EmitError``,
    ``BuildError``, ``MissingTool``, ``BenchError``, ...

    Examples
    --------
    A tool that is not installed is a :class:`~stt_codegen.system.MissingTool`, which names
    the Debian package:

    >>> import stt_codegen as stt
    >>> from stt_codegen.system import find_tool
    >>> try:
    ...     find_tool("no-such-compiler", package="gcc")
    ... except stt.ToolchainError as error:
    ...     print(error)
    no-such-compiler not found; install the Debian package gcc (apt-get install -y gcc)
    """


class UnitWarning(UserWarning):
    """A spec value that is valid but looks like a unit mistake (a rate in kHz, a length in
    millimetres where the state space is in metres); raised as a warning, not an error, at
    loading (:func:`stt_codegen.load_spec`, :meth:`stt_codegen.Spec.from_dict`).

    Its message is ``"FIELD: REASON"``, as a :class:`SpecError`'s. The command line prints
    it as one line, ``warning: FIELD: REASON``, on standard error. Silence it with
    ``warnings.simplefilter("ignore", stt_codegen.UnitWarning)``.

    Examples
    --------
    >>> import warnings
    >>> import stt_codegen as stt
    >>> task = {"name": "slow", "prescribed_time": 8.0, "controller": {"rate_hz": 0.5},
    ...         "state_space": {"lower": [0.0, 0.0], "upper": [5.0, 5.0]},
    ...         "initial": {"lower": [0.0, 0.0], "upper": [0.5, 0.5]},
    ...         "target": {"lower": [4.5, 4.5], "upper": [5.0, 5.0]}}
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     spec = stt.Spec.from_dict(task)
    >>> print(caught[0].message)
    controller.rate_hz: 0.5 Hz is below 1 Hz (a rate meant in kHz? 1 kHz is 1000)
    """


def number_text(value: float, digits: int = 12) -> str:
    """A number as the toolkit's messages print it: ``g`` format, ``digits`` significant
    digits.

    Twelve digits show every value a user types as typed (``0.1``, ``1234567.5``) and drop
    the last-bit noise of arithmetic on it (``0.45 - 0.1`` is ``0.35``, not
    ``0.35000000000000003``; ``87.35000000000001`` is ``87.35``). A message that compares
    two numbers close enough to look equal prints them with
    :func:`stt_codegen.rounding.distinct` instead.

    Parameters
    ----------
    value : float
        Any real number (an int prints as itself; ``inf`` and ``nan`` as ``inf``, ``nan``).
    digits : int, optional
        Significant digits at most (default 12).

    Returns
    -------
    str
    """
    return f"{value:.{digits}g}"


__all__ = ["DesignError", "SpecError", "SttError", "ToolchainError", "UnitWarning",
           "number_text"]
