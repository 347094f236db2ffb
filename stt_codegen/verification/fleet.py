"""Every check of a fleet's design (``stt-codegen verify FLEET``, docs/fleets.md).

Each robot's design is verified as a single design is (:func:`~.command.verify`: the
lemmas, its plant, its tube's certificate certified again, its sampled loop), against its
own spec, which holds the robots placed before it as moving obstacles. Every pair's
separation is then certified for every ``t >= 0`` again, from the certificates that
verification recomputes (not the designer's), by the fleet certificate
(:func:`~stt_codegen.design.fleet.certify_fleet`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

from ..design.certificate.fleet import PairMargin, robot_tube
from ..design.fleet import CHUNK_SECONDS, FleetDesign, certify_fleet, design_fleet
from ..design.search import check_tube
from ..display import Rows, text
from ..progress import ProgressCallback, Reporter
from ..proofs.check import VerificationReport
from ..spec.fleet import FleetSpec
from .command import verify

__all__ = ["FleetVerification", "pair_json", "verify_fleet"]


def pair_json(pair: PairMargin) -> dict[str, Any]:
    """A pair's separation as JSON (``pair``, ``passed``, ``margin``, ``interval`` with
    ``None`` for an unbounded end, ``dimension``, ``intervals``), as ``design --json`` and
    ``verify --json`` print it."""
    return {"pair": list(pair.pair), "passed": pair.passed, "margin": pair.margin,
            "interval": [pair.t_start, pair.t_end if math.isfinite(pair.t_end) else None],
            "dimension": pair.dim, "intervals": pair.intervals}


@dataclass(frozen=True)
class FleetVerification:
    """The verification of a fleet: every robot's report and every pair's separation.

    Attributes
    ----------
    fleet : str
        The fleet's name.
    robots : dict of str to VerificationReport
        Per robot, in the fleet's order, :func:`~stt_codegen.verify` of its design.
    pairs : tuple of PairMargin
        Every pair's separation for every ``t >= 0``, certified again from the recomputed
        certificates, narrowest first.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> report = stt.verify_fleet(stt.design_fleet("swap-fleet"))
    >>> report.passed, sorted(report.robots), len(report.pairs)
    (True, ['east', 'west'], 1)
    """

    fleet: str
    robots: dict[str, VerificationReport]
    pairs: tuple[PairMargin, ...]

    @property
    def passed(self) -> bool:
        """Every robot's checks and every pair's separation passed."""
        return (all(r.passed for r in self.robots.values())
                and all(p.passed for p in self.pairs))

    def summary_rows(self) -> Rows:
        """The rows of :meth:`summary`: per robot its counts and failures, then the pairs
        (the narrowest, and every failed one)."""
        rows: list[tuple[str, str]] = []
        for name, report in self.robots.items():
            failed = report.failed
            rows.append((name, f"{len(report.checks) - len(failed)} of {len(report.checks)} "
                               f"checks passed" + (f", {len(failed)} FAILED: "
                                                   + ", ".join(c.name for c in failed)
                                                   if failed else "")))
        if self.pairs:
            bad = [p for p in self.pairs if not p.passed]
            rows.append(("pairs", f"{len(self.pairs) - len(bad)} of {len(self.pairs)} "
                                  "separated for every t >= 0"))
            rows.append(("narrowest pair", self.pairs[0].detail))
            rows.extend(("FAIL", p.detail) for p in bad)
        return rows

    def summary(self) -> str:
        """The report in a few lines (what ``stt-codegen verify FLEET`` prints)."""
        verdict = "every check passed" if self.passed else "a check FAILED"
        return text(f"Fleet {self.fleet}: {verdict}", self.summary_rows())

    def to_json(self) -> dict[str, Any]:
        """``{"fleet", "passed", "robots": {name: [checks]}, "pairs": [...]}``, the
        output of ``verify --json`` for a fleet."""
        return {"fleet": self.fleet, "passed": self.passed,
                "robots": {name: r.to_json() for name, r in self.robots.items()},
                "pairs": [pair_json(p) for p in self.pairs]}

    def __str__(self) -> str:
        """Every robot's every check, then every pair."""
        parts = [f"== {name}\n{report}" for name, report in self.robots.items()]
        parts.append("== pairs\n" + "\n".join(
            f"{'PASS' if p.passed else 'FAIL'}  {p.detail}" for p in self.pairs))
        return "\n".join(parts)


def verify_fleet(fleet: FleetDesign | FleetSpec | str | os.PathLike, *,
                 progress: ProgressCallback | None = None,
                 cache: bool = True) -> FleetVerification:
    """Verify every robot of a fleet and certify every pair's separation again.

    Parameters
    ----------
    fleet : FleetDesign, FleetSpec, str or path
        A design from :func:`stt_codegen.design_fleet`, or what it takes (designed first).
    progress : callable, optional
        Called with a :class:`~stt_codegen.progress.Progress` before each robot (stage
        ``"robot <name>"``) and before the pairs (``"pairs"``); the last event is
        ``("done", 1.0)``.
    cache : bool
        As :func:`stt_codegen.verify` (the proof cache of the design-independent lemmas).

    Returns
    -------
    FleetVerification
        ``passed`` when every robot's report and every pair passed.

    Raises
    ------
    DesignError
        A fleet given as a spec has no certified design.
    SpecError
        A bad fleet file.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> report = stt.verify_fleet("swap-fleet")
    >>> print(report.summary())                                     # doctest: +ELLIPSIS
    Fleet swap-fleet: every check passed
      east: ...45 of 45 checks passed
      west: ...45 of 45 checks passed
      pairs: ...1 of 1 separated for every t >= 0
      narrowest pair: east and west: bodies apart by >= ...
    """
    designed = fleet if isinstance(fleet, FleetDesign) else design_fleet(fleet)
    robots = designed.fleet.robots
    step = Reporter(progress)
    reports: dict[str, VerificationReport] = {}
    tubes = {}
    for k, robot in enumerate(robots):
        step(f"robot {robot.name}", k / (len(robots) + 1),
             f"robot {robot.name} ({k + 1}/{len(robots)})")
        design = designed.designs[robot.name]
        reports[robot.name] = verify(design, cache=cache)
        # the pairs from the certificate verification recomputes, not the designer's
        certificate = check_tube(design.tube, design.spec).certificate
        tubes[robot.name] = robot_tube(design.tube, certificate).finer(CHUNK_SECONDS)
    step("pairs", len(robots) / (len(robots) + 1), f"{len(robots) * (len(robots) - 1) // 2} "
                                                  "pairs")
    pairs = certify_fleet(designed.fleet, designed.designs, tubes)
    step("done", 1.0)
    return FleetVerification(designed.fleet.name, reports, pairs)
