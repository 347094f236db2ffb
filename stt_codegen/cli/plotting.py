"""``--plot PNG`` and ``--dims I,J`` of the commands that draw a figure (``design``,
``simulate``; ``demo`` takes ``--dims`` for its plots).

One place for the options, their early checks (before any long computation) and the atomic
write of the figure.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import SpecError
from ..system import atomic_write

if TYPE_CHECKING:
    from ..design.result import Design
    from ..errors import DesignError
    from ..spec.loader import Spec

__all__ = ["add_dims_argument", "add_plot_argument", "check_plot_folder", "design_to_plot",
           "plot_dims", "write_plot"]


def add_dims_argument(p: argparse.ArgumentParser) -> None:
    """``--dims I,J``: the state dimensions of the plot's arena.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--dims`` (a string, parsed by :func:`plot_dims`).
    """
    p.add_argument("--dims", metavar="I,J", help="state dimensions of the plot's arena, "
                   "zero-based (default: 0,1)")


def add_plot_argument(p: argparse.ArgumentParser, what: str) -> None:
    """``--plot PNG``: write a figure of ``what`` (words for the help text); and
    ``--dims``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--plot`` and ``--dims``.
    what : str
        What the figure shows, for the help text.
    """
    p.add_argument("--plot", metavar="PNG", help=f"write a figure of {what}")
    add_dims_argument(p)


def check_plot_folder(args: argparse.Namespace) -> None:
    """Refuse a ``--plot`` path whose folder does not exist, before any work.

    Raises
    ------
    SpecError
        Field ``plot`` (shown as ``--plot``).
    """
    if getattr(args, "plot", None):
        folder = Path(args.plot).parent
        if not folder.is_dir():
            raise SpecError("plot", f"folder {str(folder)!r} does not exist")


def plot_dims(args: argparse.Namespace, spec: Spec) -> tuple[int, int]:
    """``--dims`` for ``spec``, checked before any work (default ``(0, 1)``).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``dims`` (``"I,J"`` or ``None``).
    spec : Spec
        The spec whose state dimension bounds ``I`` and ``J``.

    Returns
    -------
    tuple of int, length 2
        The two zero-based state dimensions of the figure.

    Raises
    ------
    SpecError
        Field ``dims`` (shown as ``--dims``): not two distinct dimensions of the state
        space.
    """
    from ..runtime.dims import parse_dims
    return parse_dims(args.dims, spec.dimension)


def write_plot(args: argparse.Namespace, draw: Callable[[Path], object]) -> None:
    """Write the figure ``draw(path)`` saves to ``--plot``, atomically; nothing without
    ``--plot``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``plot`` (a PNG path or ``None``).
    draw : callable
        ``draw(path)`` saves the figure to ``path`` (a temporary file, renamed to ``--plot``
        when complete).
    """
    if args.plot:
        atomic_write(Path(args.plot), draw, field="plot")


def write_rejected_plot(args: argparse.Namespace, spec: Spec, error: DesignError,
                        dims: tuple[int, int]) -> None:
    """With ``--plot``, when there is no design: write the figure of the best rejected
    tube (``error.tried``) and say so on standard error, or say why there is no figure."""
    if not args.plot:
        return
    if error.tried is None:
        print(f"no plot written to {args.plot}: no tube was tried", file=sys.stderr)
        return
    from ..runtime.plots import plot_rejected
    write_plot(args, lambda path: plot_rejected(spec, error, path, dims=dims))
    print(f"plot written to {args.plot}: it shows the best rejected tube", file=sys.stderr)


def design_to_plot(args: argparse.Namespace, check: Callable[[Spec], None] | None = None
                   ) -> tuple[Design, tuple[int, int]]:
    """Load ``SPEC``, check ``--plot`` and ``--dims`` (and ``check``) before any work, and
    design the tube (:func:`~.common.design_spec`); with no design,
    :func:`write_rejected_plot` first.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``spec``, ``plot``, ``dims`` and, optionally, ``json``.
    check : callable, optional
        ``check(spec)``, the command's own checks of the loaded spec (raising
        :class:`~stt_codegen.errors.SpecError`), before the design.

    Returns
    -------
    design : Design
        The certified design.
    dims : tuple of int, length 2
        The arena's dimensions of the figure.

    Raises
    ------
    SpecError
        A bad spec, ``--plot`` folder or ``--dims``, or what ``check`` refuses.
    DesignError
        No design (exit 1).
    """
    from ..errors import DesignError
    from ..spec.loader import load_spec
    from .common import design_spec
    check_plot_folder(args)
    spec = load_spec(args.spec)
    dims = plot_dims(args, spec)
    if check is not None:
        check(spec)
    try:
        return design_spec(spec, args), dims
    except DesignError as exc:
        write_rejected_plot(args, spec, exc, dims)
        raise
