"""``stt-codegen generate SPEC -o DIR``: write the standalone controllers of a spec."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..codegen.options import LANGUAGES, PRECISIONS, parse_options
from ..codegen.tube_data import parse_capacity
from ..errors import SpecError
from .common import add_spec_argument, add_tube_data_argument, load_and_design

__all__ = ["cmd_generate", "configure_generate"]


def cmd_generate(args: argparse.Namespace) -> int:
    """0 written, 1 no design, 2 bad input, 3 code generator failure.

    Parameters
    ----------
    args : argparse.Namespace
        ``spec``, ``out_dir``, ``languages`` (comma-separated; ``None``: C and Python),
        ``precision`` and ``tube_data`` (``None`` or ``"SEGMENTS,WINDOWS"``).

    Returns
    -------
    int
        0 when the files are written.

    Raises
    ------
    SpecError
        A bad spec, language list, precision or capacity (exit code 2).
    DesignError
        No design (exit code 1).
    ToolchainError
        The code generator failed (exit code 3).
    """
    from .fleet import fleet_generate, fleet_of
    capacity = None if args.tube_data is None else parse_capacity(args.tube_data)
    if args.languages is None:
        args.languages = ",".join(LANGUAGES)
    fleet = fleet_of(args)            # a fleet file: one design per robot (docs/fleets.md)
    if fleet is not None:
        if capacity is not None:
            raise SpecError("tube_data", "a fleet's robots run their designed tubes: "
                                         "--tube-data is for one spec")
        return fleet_generate(args, fleet)
    from ..codegen.api import generate
    parse_options(args.languages, args.precision, capacity)   # bad options fail first
    design = load_and_design(args)
    files = generate(design, Path(args.out_dir), languages=args.languages,
                     precision=args.precision, tube_data=capacity)
    form = "" if capacity is None else (f", the tube as data: {capacity.segments} segments, "
                                        f"{capacity.windows} windows")
    print(f"wrote {len(files)} files for {design.spec.name} ({args.languages}, "
          f"{args.precision}{form}) into {args.out_dir}")
    if design.spec.sensing is not None and capacity is None:
        # a spec that replans at run time, written with its designed tube only
        print(f"note: {design.spec.name} has [sensing]: this controller runs its designed "
              f"tube only; --tube-data writes the one that takes the tubes replanned around "
              f"sensed obstacles (docs/sensing.md, \"The tube as data\")")
    return 0


def configure_generate(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen generate``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``SPEC``, ``--out``, ``--lang``, ``--precision``,
        ``--tube-data`` and the ``handler`` :func:`cmd_generate`.
    """
    add_spec_argument(p)
    p.add_argument("-o", "--out", dest="out_dir", required=True, metavar="DIR",
                   help="output folder (created; only files of a previous generation are replaced)")
    p.add_argument("--lang", dest="languages", default=None, metavar="LANGS",
                   help=f"comma-separated subset of: {','.join(LANGUAGES)} (default: both; "
                        f"c with --tube-data)")
    p.add_argument("--precision", default="double", choices=PRECISIONS,
                   help="floating-point type of the C code (default: %(default)s)")
    add_tube_data_argument(p)
    p.set_defaults(handler=cmd_generate)
