"""``stt-codegen verify SPEC``: every check of a spec's designed tube, with its evidence."""

from __future__ import annotations

import argparse
import json

from .common import add_json_argument, add_quiet_argument, add_spec_argument, design_spec, \
    progress_bar

__all__ = ["cmd_verify", "configure_verify"]


def cmd_verify(args: argparse.Namespace) -> int:
    """0 every check passed, 1 a check failed or no design, 2 bad input.

    Parameters
    ----------
    args : argparse.Namespace
        ``spec``, ``plant`` (a plant model or ``None`` for the spec's), ``json``,
        ``all`` (every check instead of the summary: the failures and the key figures,
        :meth:`~stt_codegen.proofs.check.VerificationReport.summary`), ``quiet`` (no
        progress bar) and ``no_cache`` (prove the design-independent lemmas again).

    Returns
    -------
    int
        0 every check passed, 1 a check failed.

    Raises
    ------
    SpecError
        A bad spec or plant model (exit code 2).
    DesignError
        No design (exit code 1).
    """
    from ..spec.loader import load_spec
    from ..verification.command import spec_for_plant, verify
    from .fleet import fleet_of, fleet_verify
    fleet = fleet_of(args)            # a fleet file: every robot and pair (docs/fleets.md)
    if fleet is not None:
        return fleet_verify(args, fleet)
    design = design_spec(spec_for_plant(load_spec(args.spec), args.plant), args)
    with progress_bar(args, "verify") as progress:
        report = verify(design, plant=args.plant, progress=progress, cache=not args.no_cache)
    if args.json:
        print(json.dumps(report.to_json(), indent=2))
    else:
        print(str(report) if args.all else report.summary())
        if design.output_warning is not None:
            print(f"  warning: {design.output_warning}")
    return 0 if report.passed else 1


def configure_verify(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen verify``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``SPEC``, ``--json``, ``--all``, ``--quiet``,
        ``--plant``, ``--no-cache`` and the ``handler`` :func:`cmd_verify`.
    """
    from ..spec.plants import MODELS_WITH_EQUATIONS
    add_spec_argument(p)
    add_json_argument(p, "print a JSON list of checks")
    p.add_argument("--all", action="store_true",
                   help="print every check with its evidence (default: the failures and "
                        "the key figures)")
    add_quiet_argument(p)
    p.add_argument("--plant", default=None, metavar="MODEL",
                   help=f"plant for Assumption 2 and the sampled check's bounds "
                        f"({', '.join(MODELS_WITH_EQUATIONS)}; default: the spec's)")
    p.add_argument("--no-cache", action="store_true",
                   help="prove the spec-independent lemmas again instead of reading the "
                        "proof cache (~/.cache/stt-codegen; see docs/verification.md)")
    p.set_defaults(handler=cmd_verify)
