"""The result object shared by every verification check."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable


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
    """Return ``True`` when every check in ``checks`` passed."""
    return all(c.passed for c in checks)


def format_report(checks: Iterable[Check]) -> str:
    """One line per check, ``[PASS]``/``[FAIL]`` first."""
    return "\n".join(str(c) for c in checks)
