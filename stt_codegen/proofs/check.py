"""The result objects of verification: one :class:`Check`, and a :class:`VerificationReport`."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any, Iterable

from ..display import Rows, markdown, shorten, text

__all__ = ["Check", "VerificationReport", "all_passed", "format_report"]

#: Families of checks counted on one line of :meth:`VerificationReport.summary`.
FAMILIES_A_LINE = 6


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
    >>> report
    VerificationReport(spec='corridor', checks=2, passed=1, failed=1)
    >>> print(report.summary())
    corridor: 1 of 2 checks passed, 1 FAILED
      passed: tube 1/2
      FAIL:   tube.avoids_obstacle_0: meets it at t = 2.1 s
      (every check: stt-codegen verify --all, or print(report))
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

    def summary_rows(self) -> Rows:
        """The rows of :meth:`summary`: the checks passed by family (the name up to its
        first word after a dot: ``lemma3.3``, ``tube``), every failed check, and the key figures the checks carry: the smallest
        certified margin of the tube, the tube's move per sample, and the sampled loop's
        checks (``sampled.*``, ``cascade.sampled``, ``cascade.delay``, ``cascade.input_bound``).

        Returns
        -------
        list of (str, str)
        """
        families: dict[str, list[bool]] = {}
        for c in self.checks:       # "lemma3.3.reach.continuity": family "lemma3.3"
            family = re.match(r"[^.\[]+(\.\d+)*", c.name)
            families.setdefault(family.group(0) if family else c.name, []).append(c.passed)
        counts = [f"{name} {sum(v)}/{len(v)}" for name, v in families.items()]
        rows = [("passed" if k == 0 else "", ", ".join(counts[k:k + FAMILIES_A_LINE]))
                for k in range(0, len(counts), FAMILIES_A_LINE)]
        rows += [("FAIL", f"{c.name}: {c.detail}") for c in self.failed]
        margins = [(c.data["margin"], c.name) for c in self.checks
                   if c.name.startswith("tube.") and isinstance(c.data.get("margin"), float)
                   and math.isfinite(c.data["margin"])]
        if margins:
            margin, name = min(margins)
            rows.append(("smallest margin", f"{margin:.4g} ({name})"))
        for c in self.checks:
            if c.passed and (c.name == "tube.sampling_rate" or c.name.startswith(
                    ("sampled.", "cascade.sampled", "cascade.delay", "cascade.input_bound"))):
                rows.append(("PASS", f"{c.name}: {c.detail}"))
        return rows

    def summary(self) -> str:
        """The report in a few lines: the counts, the failures and the key figures (what
        ``stt-codegen verify`` prints; ``str(report)`` and ``--all`` have every check).

        Returns
        -------
        str
            A title line, then one line a row of :meth:`summary_rows` (each cut to a
            screen's width), then where to find every check.
        """
        return text(self._title(), self.summary_rows()) + \
            "\n  (every check: stt-codegen verify --all, or print(report))"

    def _title(self) -> str:
        failed = len(self.failed)
        return (f"{self.spec}: {len(self.checks) - failed} of {len(self.checks)} checks "
                f"passed" + (f", {failed} FAILED" if failed else ""))

    def _repr_markdown_(self) -> str:
        """The summary as a Markdown table (Jupyter's rich display)."""
        return markdown(self._title(), self.summary_rows())

    def __repr__(self) -> str:
        failed = len(self.failed)
        return (f"VerificationReport(spec={self.spec!r}, checks={len(self.checks)}, "
                f"passed={len(self.checks) - failed}, failed={failed})")

    def to_json(self) -> list[dict[str, Any]]:
        """``[{"name", "passed", "detail"}, ...]``, the output of ``verify --json``."""
        return [{"name": c.name, "passed": c.passed, "detail": c.detail} for c in self.checks]

    def __str__(self) -> str:
        """One line per check, ``PASS``/``FAIL`` first, then ``N passed, M failed``."""
        lines = [f"{'PASS' if c.passed else 'FAIL'}  {c.name}: {c.detail}" for c in self.checks]
        failed = len(self.failed)
        return "\n".join(lines + [f"{len(self.checks) - failed} passed, {failed} failed"])
