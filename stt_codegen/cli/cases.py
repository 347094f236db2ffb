"""``stt-codegen cases``: list the bundled specs, one name a line."""

from __future__ import annotations

import argparse

__all__ = ["cmd_cases", "configure_cases"]


def cmd_cases(args: argparse.Namespace) -> int:
    """Print the bundled specs' names; exit 0.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments (none are read).

    Returns
    -------
    int
        0.
    """
    from ..cases import bundled_cases
    for name in bundled_cases():
        print(name)
    return 0


def configure_cases(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen cases`` (none).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; its ``handler`` is set to :func:`cmd_cases`.
    """
    p.set_defaults(handler=cmd_cases)
