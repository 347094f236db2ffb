"""``stt-codegen generate SPEC -o DIR``: write the standalone controllers of a spec."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..codegen.options import LANGUAGES, PRECISIONS, parse_options
from .common import add_spec_argument, load_and_design

__all__ = ["cmd_generate", "configure_generate"]


def cmd_generate(args: argparse.Namespace) -> int:
    """0 written, 1 no design, 2 bad input, 3 code generator failure.

    Parameters
    ----------
    args : argparse.Namespace
        ``spec``, ``out_dir``, ``languages`` (comma-separated) and ``precision``.

    Returns
    -------
    int
        0 when the files are written.

    Raises
    ------
    SpecError
        A bad spec, language list or precision (exit code 2).
    DesignError
        No design (exit code 1).
    ToolchainError
        The code generator failed (exit code 3).
    """
    from .fleet import fleet_generate, fleet_of
    fleet = fleet_of(args)            # a fleet file: one design per robot (docs/fleets.md)
    if fleet is not None:
        return fleet_generate(args, fleet)
    from ..codegen.api import generate
    parse_options(args.languages, args.precision)   # bad options fail before the design
    design = load_and_design(args)
    files = generate(design, Path(args.out_dir), languages=args.languages,
                     precision=args.precision)
    print(f"wrote {len(files)} files for {design.spec.name} ({args.languages}, "
          f"{args.precision}) into {args.out_dir}")
    return 0


def configure_generate(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen generate``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``SPEC``, ``--out``, ``--lang``, ``--precision`` and
        the ``handler`` :func:`cmd_generate`.
    """
    add_spec_argument(p)
    p.add_argument("-o", "--out", dest="out_dir", required=True, metavar="DIR",
                   help="output folder (created; only files of a previous generation are replaced)")
    p.add_argument("--lang", dest="languages", default=",".join(LANGUAGES), metavar="LANGS",
                   help="comma-separated subset of: %(default)s")
    p.add_argument("--precision", default="double", choices=PRECISIONS,
                   help="floating-point type of the C code (default: %(default)s)")
    p.set_defaults(handler=cmd_generate)
