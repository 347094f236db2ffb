"""``stt-codegen check``: regenerate ``generated/`` and compare it with the committed one."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import SpecError

__all__ = ["cmd_check", "configure_check"]


def cmd_check(args: argparse.Namespace) -> int:
    """``stt-codegen check [--root generated] [--update]``: 0 identical, 1 drift.

    Parameters
    ----------
    args : argparse.Namespace
        ``root`` (the folder of the committed output) and ``update`` (rewrite it instead of
        comparing).

    Returns
    -------
    int
        0 identical (or rewritten), 1 drift (the differences on standard output).

    Raises
    ------
    SpecError
        ``--root``: no such folder to compare (exit 2; run from the repository's root).
    """
    from ..codegen.bundled import drift, update_generated, version_note
    root = Path(args.root)
    if not args.update and not root.is_dir():
        raise SpecError("--root", f"no folder {root.as_posix()}/ here to compare: run "
                                  "`stt-codegen check` from the repository's root, or name "
                                  "the committed output's folder with --root")
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


def configure_check(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen check``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--root`` and ``--update`` and the ``handler``
        :func:`cmd_check`.
    """
    p.add_argument("--root", default="generated", metavar="DIR",
                   help="folder of the committed output (default: %(default)s)")
    p.add_argument("--update", action="store_true", help="rewrite the folder instead of comparing")
    p.set_defaults(handler=cmd_check)
