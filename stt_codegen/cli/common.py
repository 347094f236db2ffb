"""What several commands share: their common arguments, the design step and the document
printed with ``--json`` when there is no design.

The library is imported inside the functions that need it, so that importing this module
(for ``stt-codegen --help`` or ``cases``) costs nothing.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from ..errors import DesignError

if TYPE_CHECKING:
    from ..design.result import Design
    from ..progress import Progress
    from ..runtime.sensed import WalkingObstacle
    from ..runtime.simulate import SimulationResult
    from ..spec.loader import Spec

__all__ = ["add_backend_argument", "add_json_argument", "add_quiet_argument",
           "add_seed_argument", "add_spec_argument", "add_tube_data_argument", "checked_seed",
           "closed_loop", "design_spec", "load_and_design", "print_json", "progress_bar"]

#: Seconds of work before the progress bar appears (shorter work shows none).
BAR_DELAY = 2.0


def add_spec_argument(p: argparse.ArgumentParser) -> None:
    """The positional ``SPEC``: a bundled case name or a spec file.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets the positional ``spec``.
    """
    p.add_argument("spec", metavar="SPEC", help="bundled case name or spec file")


def add_json_argument(p: argparse.ArgumentParser, text: str = "print one JSON object") -> None:
    """``--json``: print one JSON document on standard output instead of text.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--json`` (``args.json``, a bool).
    text : str, optional
        The option's help text.
    """
    p.add_argument("--json", action="store_true", help=text)


def add_quiet_argument(p: argparse.ArgumentParser) -> None:
    """``--quiet``: no progress bar on standard error.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--quiet`` (``args.quiet``, a bool).
    """
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar on standard error (it is drawn only on a terminal)")


@contextmanager
def progress_bar(args: argparse.Namespace, what: str) -> Iterator[Callable[[Progress], None] | None]:
    """A tqdm bar on standard error that draws the :class:`~stt_codegen.progress.Progress`
    events of long work, shown after :data:`BAR_DELAY` seconds, only when standard error
    is a terminal and without ``--quiet``; removed at the end.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments; ``quiet`` (if present) turns the bar off.
    what : str
        The bar's label (``"design"``).

    Yields
    ------
    callable or None
        The ``progress`` callback to pass to the library, ``None`` for no bar.
    """
    if getattr(args, "quiet", False) or not sys.stderr.isatty():
        yield None
        return
    from tqdm import tqdm
    started = time.monotonic()
    with tqdm(total=100, desc=what, file=sys.stderr, leave=False, delay=BAR_DELAY,
              bar_format="{desc}: {percentage:3.0f}%|{bar:20}| {elapsed}{postfix}") as bar:
        def show(event: Progress) -> None:
            bar.n = round(100 * event.fraction)
            bar.set_postfix_str(event.message, refresh=False)
            if time.monotonic() - started >= BAR_DELAY:     # short work draws no bar
                bar.refresh()
        yield show


def add_backend_argument(p: argparse.ArgumentParser) -> None:
    """``--backend``: the controller implementation (``stt_codegen.runtime.backends``).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--backend`` (the registered backends' names; default
        ``None``: the library's, :func:`stt_codegen.runtime.backends.default_backend`).
    """
    from ..runtime.backends import backend_names
    p.add_argument("--backend", default=None, choices=backend_names(),
                   help="controller implementation (default: c where a C compiler is "
                        "found, else reference)")


def print_json(data: Any) -> None:
    """Print ``data`` as one indented JSON document with sorted keys.

    Parameters
    ----------
    data : Any
        A JSON-serialisable object (dicts, lists, str, numbers, bool, None).
    """
    print(json.dumps(data, indent=2, sort_keys=True))


def add_seed_argument(p: argparse.ArgumentParser) -> None:
    """``--seed N``: the disturbance seed, checked by :func:`checked_seed`.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--seed`` (an int, default 0).
    """
    p.add_argument("--seed", type=int, default=0, metavar="N",
                   help="disturbance seed, an integer in [0, 2**32) (default: 0)")


def checked_seed(args: argparse.Namespace) -> int:
    """``--seed``, checked before any work (the library's rule,
    :func:`stt_codegen.runtime.plants.check_seed`).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``seed``.

    Returns
    -------
    int
        The seed, in ``[0, 2**32)``.

    Raises
    ------
    SpecError
        Field ``seed`` (shown as ``--seed``): not in ``[0, 2**32)``.
    """
    from ..runtime.plants import check_seed
    return check_seed(args.seed)


def no_design_document(spec: Spec, error: DesignError) -> dict[str, Any]:
    """What every command that designs prints with ``--json`` when there is no design.

    Returns
    -------
    dict
        ``spec`` (the name), ``designed`` (``False``), ``reason`` (the message of the
        error) and ``kind`` (the :class:`~stt_codegen.design.failures.FailureKind` value,
        e.g. ``"walled off"``, or ``None``). A design is ``Design.to_json()``, with
        ``designed`` ``True``.
    """
    kind = getattr(error.kind, "value", None)
    return {"spec": spec.name, "designed": False, "reason": str(error), "kind": kind}


def design_spec(spec: Spec, args: argparse.Namespace) -> Design:
    """Design the tube of ``spec`` for a command; with ``--json``, when there is no design,
    print :func:`no_design_document` on standard output first.

    Parameters
    ----------
    spec : Spec
        The loaded spec.
    args : argparse.Namespace
        Parsed arguments; ``json`` (if present) asks for the document on no design,
        ``quiet`` (if present) turns the progress bar off (:func:`progress_bar`).

    Returns
    -------
    Design
        The certified design (:func:`stt_codegen.design.search.design_tube`).

    Raises
    ------
    DesignError
        No certified tube exists for the spec: exit code 1, the reason on standard error.
    """
    from ..design.search import design_tube
    try:
        with progress_bar(args, "design") as progress:
            return design_tube(spec, progress=progress)
    except DesignError as exc:
        if getattr(args, "json", False):
            print_json(no_design_document(spec, exc))
        raise


def load_and_design(args: argparse.Namespace) -> Design:
    """:func:`design_spec` of the spec ``SPEC`` names (a bundled case or a file).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``spec`` (a bundled case name or a spec file) and, optionally,
        ``json``.

    Returns
    -------
    Design
        The certified design of the spec.

    Raises
    ------
    SpecError
        The spec is invalid or cannot be found.
    DesignError
        As :func:`design_spec`.
    """
    from ..spec.loader import load_spec
    return design_spec(load_spec(args.spec), args)


def add_tube_data_argument(p: argparse.ArgumentParser) -> None:
    """``--tube-data [SEGMENTS,WINDOWS]`` (``generate``, ``embedded``): the code whose tube
    is data (:mod:`stt_codegen.codegen.tube_data`); ``args.tube_data`` is ``None`` or the
    text.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser.
    """
    from ..codegen.tube_data import DEFAULT_CAPACITY
    default = f"{DEFAULT_CAPACITY.segments},{DEFAULT_CAPACITY.windows}"
    p.add_argument("--tube-data", nargs="?", metavar="SEGMENTS,WINDOWS", const=default,
                   help="code whose tube is data (C, and Python with generate), replaced "
                        "at run time by its switch, holding up to SEGMENTS reach segments "
                        "and WINDOWS circumvent windows "
                        f"(default {default}; docs/sensing.md)")


def closed_loop(design: Design, obstacles: Callable[[], Sequence[WalkingObstacle]],
                backend: str | None, horizon: float | None = None,
                seed: int = 0) -> SimulationResult:
    """The closed loop a command runs for ``design``: among the obstacles ``obstacles()``
    returns, revealed only by sensing and replanning the tube (``simulate_sensed``), for a
    spec with ``[sensing]``; else the design's tube alone (``simulate``, the cascade's for
    a second-order plant). ``obstacles`` is called only for a spec with ``[sensing]``."""
    if design.spec.sensing is None:
        from ..runtime.simulate import simulate
        return simulate(design, backend=backend, horizon=horizon, seed=seed)
    from ..runtime.sensed import simulate_sensed
    return simulate_sensed(design, obstacles(), backend=backend, horizon=horizon, seed=seed)
