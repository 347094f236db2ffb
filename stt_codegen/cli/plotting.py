"""``--plot PNG`` of the commands that draw a figure (``design``, ``simulate``).

One place for the option, the early check of its folder (before any long computation) and
the atomic write; an option of the figure (a choice of dimensions, say) is added here and
passed on by :func:`write_plot`'s callers.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

from ..errors import SpecError
from ..system import atomic_write


def add_plot_argument(p: argparse.ArgumentParser, what: str) -> None:
    """``--plot PNG``: write a figure of ``what`` (words for the help text)."""
    p.add_argument("--plot", metavar="PNG", help=f"write a figure of {what}")


def check_plot_folder(args: argparse.Namespace) -> None:
    """Refuse a ``--plot`` path whose folder does not exist, before any work.

    Raises
    ------
    SpecError
        Field ``plot`` (shown as ``--plot``).
    """
    if args.plot:
        folder = Path(args.plot).parent
        if not folder.is_dir():
            raise SpecError("plot", f"folder {str(folder)!r} does not exist")


def write_plot(args: argparse.Namespace, draw: Callable[[Path], object]) -> None:
    """Write the figure ``draw(path)`` saves to ``--plot``, atomically; nothing without
    ``--plot``."""
    if args.plot:
        atomic_write(Path(args.plot), draw, field="plot")
