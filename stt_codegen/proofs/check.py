"""The result objects of verification: one :class:`Check`, and a :class:`VerificationReport`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable

__all__ = ["Check", "VerificationReport", "all_passed", "format_report"]


@dataclass(frozen=True)
class Check:
    """Outcome of one verification check.

    Parameters
    ----------
    name : str
        Stable, dotted identifier, e.g. ``"lemma3.3.reach.continuity"``.
    passed : bool
        ``True`` when the property was proved (or, for numeric checks, held on
        every tested case).
    detail : str
        The evidence in words: the bound found, the expression, or the point or
        interval where the property fails.
    data : dict
        Machine-readable evidence (numbers as ``float``, expressions as
        ``str``), for reports and tests.
    """

    name: str
    passed: bool
    detail: str
    data: dict[str, Any] = field(default_factory=dict)

    def __str__(self) -> str:
        return f"[{'PASS' if self.passed else 'FAIL'}] {self.name}: {self.detail}"


def all_passed(checks: Iterable[Check]) -> bool:
    """Return ``True`` when every check in ``checks`` passed.

    Parameters
    ----------
    checks : iterable of Check
        The checks.

    Returns
    -------
    bool
        Whether all passed (``True`` for none).
    """
    return all(c.passed for c in checks)


def format_report(checks: Iterable[Check]) -> str:
    """One line per check, ``[PASS]``/``[FAIL]`` first.

    Parameters
    ----------
    checks : iterable of Check
        The checks, in the order printed.

    Returns
    -------
    str
        The lines, separated by newlines.
    """
    return "\n".join(str(c) for c in checks)


@dataclass(frozen=True)
class VerificationReport:
    """Every check of one spec's designed tube (what ``stt-codegen verify`` prints).

    Parameters
    ----------
    spec : str
        The spec's name.
    checks : tuple of Check
        In the order of :func:`stt_codegen.verification.command.verify_design`; a spec for
        which no tube can be designed has the single failed check ``tube.design``.

    Examples
    --------
    What :func:`stt_codegen.verify` returns, here built by hand:

    >>> from stt_codegen.proofs.check import Check, VerificationReport
    >>> report = VerificationReport("corridor", (
    ...     Check("tube.contains_start", True, "x(0) inside at t = 0"),
    ...     Check("tube.avoids_obstacle_0", False, "meets it at t = 2.1 s")))
    >>> report.passed, [c.name for c in report.failed]
    (False, ['tube.avoids_obstacle_0'])
    >>> print(report["tube.contains_start"])
    [PASS] tube.contains_start: x(0) inside at t = 0
    """

    spec: str
    checks: tuple[Check, ...]

    @property
    def passed(self) -> bool:
        """``True`` when every check passed."""
        return all_passed(self.checks)

    @property
    def failed(self) -> tuple[Check, ...]:
        """The checks that failed, in order."""
        return tuple(c for c in self.checks if not c.passed)

    def __getitem__(self, name: str) -> Check:
        """The check named ``name`` (e.g. ``"tube.avoids_obstacle_1"``); ``KeyError`` if none."""
        for c in self.checks:
            if c.name == name:
                return c
        raise KeyError(name)

    def to_json(self) -> list[dict[str, Any]]:
        """``[{"name", "passed", "detail"}, ...]``, the output of ``verify --json``."""
        return [{"name": c.name, "passed": c.passed, "detail": c.detail} for c in self.checks]

    def __str__(self) -> str:
        """One line per check, ``PASS``/``FAIL`` first, then ``N passed, M failed``."""
        lines = [f"{'PASS' if c.passed else 'FAIL'}  {c.name}: {c.detail}" for c in self.checks]
        failed = len(self.failed)
        return "\n".join(lines + [f"{len(self.checks) - failed} passed, {failed} failed"])
