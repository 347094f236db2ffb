"""``stt-codegen demo``: every bundled case generated, compiled and run in closed loop."""

from __future__ import annotations

import argparse
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import DesignError, SpecError, SttError, ToolchainError
from ..system import atomic_write
from .common import add_backend_argument, closed_loop, design_spec
from .plotting import add_dims_argument, plot_dims
from .simulate import SUMMARY_HEADER, summary_line

if TYPE_CHECKING:
    from ..spec.loader import Spec

__all__ = ["cmd_demo", "configure_demo", "demo_jobs"]


def _run_case(name: str, spec: Spec, args: argparse.Namespace,
              dims: tuple[int, int]) -> tuple[str, bool] | tuple[None, tuple]:
    """One case of the demo: design, generate, simulate, plot; its summary line and whether
    it is satisfied, or ``(None, failure)`` with the :class:`SttError` it raised as plain
    data (an error crosses a process boundary as its kind and its words)."""
    from ..codegen.api import generate
    from ..runtime.plots import plot_run
    out = Path(args.out)

    def people():
        # the replanner is imported only by a case that senses obstacles
        from ..runtime.sensed import bundled_people
        return bundled_people(name)

    try:
        design = design_spec(spec, args)
        if spec.sensing is None:
            generate(design, out / name)
        else:
            # the controller a robot runs when it senses obstacles: its tube is data,
            # switched at run time; the bundled people are revealed only by sensing
            generate(design, out / name, languages="c", tube_data=True)
        result = closed_loop(design, people, args.backend)
        atomic_write(out / f"{name}.png",
                     lambda tmp: plot_run(design, result, tmp, dims=dims))
    except SttError as exc:
        return None, _failure(exc)
    return summary_line(result), result.satisfied


def _failure(exc: SttError) -> tuple:
    """An error as plain data (it crosses a process boundary as its kind and its words)."""
    if isinstance(exc, SpecError):
        return SpecError, exc.field, exc.reason
    return (DesignError if isinstance(exc, DesignError) else ToolchainError), str(exc)


def _run_fleet(name: str, args: argparse.Namespace) -> tuple[str, bool] | tuple[None, tuple]:
    """One bundled fleet in the demo: design, a folder per robot, every robot's closed
    loop, its figure in time slices; its summary (the certified narrowest pair, the closest approach) and whether
    it is satisfied, or ``(None, failure)`` as :func:`_run_case`."""
    from ..codegen.fleet import generate_fleet
    from ..design.fleet import design_fleet
    from ..runtime.fleet import simulate_fleet
    from ..runtime.fleet_plots import plot_fleet
    try:
        designed = design_fleet(name)
        generate_fleet(designed, Path(args.out) / name)
        run = simulate_fleet(designed, backend=args.backend)
        atomic_write(Path(args.out) / f"{name}.png",
                     lambda tmp: plot_fleet(designed, tmp, run))
    except SttError as exc:
        return None, _failure(exc)
    pair, closest = designed.narrowest, run.closest
    unmet = [n for n, r in run.results.items() if not r.satisfied]
    return (f"fleet {name}: {len(run.results)} robots, {len(designed.pairs)} pairs certified "
            f"apart for every t (narrowest {pair.margin:.3f} m, {pair.pair[0]} and "
            f"{pair.pair[1]}); {args.backend} closed loops: "
            + (f"NOT satisfied by {', '.join(unmet)}" if unmet else "every robot satisfied")
            + f", closest approach {closest.clearance:.3f} m ({closest.pair[0]} and "
            f"{closest.pair[1]} at {closest.t:.2f} s)"), run.satisfied


def _raise(failure: tuple) -> None:
    kind, *words = failure
    raise kind(*words)


def demo_jobs(args: argparse.Namespace, cases: int) -> int:
    """The number of processes that run the cases: ``--jobs``, else the CPUs this process
    may use, at most 2; never more than the cases.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``jobs`` (an int, or ``None`` for the default).
    cases : int
        The number of cases to run.

    Returns
    -------
    int
        The number of processes, in ``[1, cases]`` (1: the cases run in this process).

    Raises
    ------
    SpecError
        Field ``jobs`` (shown as ``--jobs``): below 1.
    """
    jobs = args.jobs if args.jobs is not None else min(2, len(os.sched_getaffinity(0)))
    if jobs < 1:
        raise SpecError("jobs", f"must be at least 1, got {jobs}")
    return max(1, min(jobs, cases))


def cmd_demo(args: argparse.Namespace) -> int:
    """0 every case satisfied, 1 otherwise, 3 toolchain.

    The cases run in ``--jobs`` processes (forked after the library is imported, so each
    imports nothing again); the table is printed in the order of the cases.

    Parameters
    ----------
    args : argparse.Namespace
        ``out`` (the folder for code and plots, created), ``backend``, ``dims`` and ``jobs``.

    Returns
    -------
    int
        0 every bundled case satisfied, 1 otherwise.

    Raises
    ------
    ToolchainError
        A compiler is missing or fails (exit code 3).
    SpecError
        ``--dims`` is not two distinct dimensions of a case, or ``--jobs`` is below 1 (exit
        code 2).
    DesignError
        A case has no design (exit code 1).
    """
    from ..cases import bundled_cases, bundled_fleets
    from ..spec.loader import load_spec
    from ..runtime.backends import default_backend
    args.backend = default_backend() if args.backend is None else args.backend
    specs = {name: load_spec(name) for name in bundled_cases()}
    dims = {name: plot_dims(args, spec) for name, spec in specs.items()}
    jobs = demo_jobs(args, len(specs))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    sensed = [name for name, spec in specs.items() if spec.sensing is not None]
    print(f"For every bundled case: design the tube, generate the C and Python controllers "
          f"into {out}/<case>/, and run the {args.backend} controller in closed loop"
          + (f" ({', '.join(sensed)}: the C with the tube as data, switched at run time "
             f"around people sensed on the way)" if sensed else "") + ".")
    print(SUMMARY_HEADER, flush=True)
    # what a case needs of the arguments (the parser itself does not cross processes)
    case_args = argparse.Namespace(out=args.out, backend=args.backend)
    cases = [(name, spec, case_args, dims[name]) for name, spec in specs.items()]
    fleets = bundled_fleets()
    if jobs == 1:
        outcomes = (_run_case(*case) for case in cases)
        all_ok = _print_outcomes(outcomes)
        all_ok &= _print_outcomes(_run_fleet(name, case_args) for name in fleets)
    else:
        # fork after the heavy imports: the workers start with the library loaded
        from ..codegen.api import generate  # noqa: F401
        from ..runtime.plots import plot_run  # noqa: F401
        from ..runtime.simulate import simulate  # noqa: F401
        context = multiprocessing.get_context("fork")
        with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
            # the fleets first: each is one long job beside the cases
            fleet_runs = [pool.submit(_run_fleet, name, case_args) for name in fleets]
            all_ok = _print_outcomes(pool.map(_run_case, *zip(*cases)))
            all_ok &= _print_outcomes(f.result() for f in fleet_runs)
    print(f"generated code in {out}/<case>/, plots in {out}/<case>.png"
          + "".join(f"; {name}: a folder per robot in {out}/{name}/, its plot {out}/{name}.png"
                    for name in fleets))
    return 0 if all_ok else 1


def _print_outcomes(outcomes) -> bool:
    """Print each case's line in order; raise the first case's error; all satisfied?"""
    all_ok = True
    for line, satisfied in outcomes:
        if line is None:
            _raise(satisfied)
        print(line, flush=True)
        all_ok &= satisfied
    return all_ok


def configure_demo(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen demo``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--out``, ``--backend``, ``--dims``, ``--jobs`` and
        the ``handler`` :func:`cmd_demo`.
    """
    p.add_argument("--out", default="stt-demo", metavar="DIR",
                   help="folder for the generated code and the plots (default: %(default)s)")
    add_backend_argument(p)
    add_dims_argument(p)
    p.add_argument("--jobs", type=int, metavar="N",
                   help="processes that run the cases (default: the CPUs, at most 2)")
    p.set_defaults(handler=cmd_demo)
