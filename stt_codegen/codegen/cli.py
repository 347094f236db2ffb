"""Subcommands ``generate`` and ``check`` (configured by :func:`configure_generate` and
:func:`configure_check`, listed in :data:`stt_codegen.cli.COMMANDS`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .options import LANGUAGES, PRECISIONS, parse_options


def cmd_generate(args: argparse.Namespace) -> int:
    """``stt-codegen generate SPEC -o DIR [--lang c,python] [--precision double|single]``."""
    from ..design.search import design_tube
    from ..spec.loader import load_spec
    from .api import generate
    parse_options(args.languages, args.precision)   # bad options fail before the design
    spec = load_spec(args.spec)
    design = design_tube(spec).tube
    files = generate(spec, design, Path(args.out_dir), args.languages, args.precision)
    print(f"wrote {len(files)} files for {spec.name} ({args.languages}, "
          f"{args.precision}) into {args.out_dir}")
    return 0


def cmd_check(args: argparse.Namespace) -> int:
    """``stt-codegen check [--root generated] [--update]``: 0 identical, 1 drift."""
    from .bundled import drift, update_generated, version_note
    root = Path(args.root)
    if args.update:
        update_generated(root)
        print(f"regenerated {root}/")
        return 0
    diffs = drift(root)
    print(version_note())
    if diffs:
        for text in diffs:
            sys.stdout.write(text)
        print(f"drift: {len(diffs)} file(s) under {root}/ differ from a fresh generation "
              f"(run `stt-codegen check --update` and commit)", file=sys.stderr)
        return 1
    print(f"{root}/ is up to date")
    return 0


def configure_generate(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen generate``."""
    p.add_argument("spec", metavar="SPEC", help="bundled case name or spec file")
    p.add_argument("-o", "--out", dest="out_dir", required=True, metavar="DIR",
                   help="output folder (created; only files of a previous generation are replaced)")
    p.add_argument("--lang", dest="languages", default=",".join(LANGUAGES), metavar="LANGS",
                   help="comma-separated subset of: %(default)s")
    p.add_argument("--precision", default="double", choices=PRECISIONS,
                   help="floating-point type of the C code (default: %(default)s)")
    p.set_defaults(handler=cmd_generate)


def configure_check(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen check``."""
    p.add_argument("--root", default="generated", metavar="DIR",
                   help="folder of the committed output (default: %(default)s)")
    p.add_argument("--update", action="store_true", help="rewrite the folder instead of comparing")
    p.set_defaults(handler=cmd_check)
