"""Fleet files on the command line: ``design``, ``generate``, ``simulate`` and ``verify`` of
a fleet.

A ``SPEC`` that names a bundled fleet or a TOML file with ``[[robots]]`` is a fleet
(docs/fleets.md); :func:`fleet_of` tells, and the four commands hand it to the handlers
here, thin layers over :func:`stt_codegen.design_fleet`, :func:`stt_codegen.generate_fleet`,
:func:`stt_codegen.simulate_fleet` and :func:`stt_codegen.verify_fleet`.
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path
from typing import Any, Callable

from ..cases import bundled_fleets
from .common import print_json

__all__ = ["fleet_design", "fleet_generate", "fleet_of", "fleet_simulate", "fleet_verify"]


def fleet_of(args: argparse.Namespace) -> Any:
    """The fleet ``args.spec`` names, or ``None`` for a single spec.

    Parameters
    ----------
    args : argparse.Namespace
        With ``spec``: a bundled name or a file.

    Returns
    -------
    FleetSpec or None
        ``None`` when ``spec`` is no bundled fleet and no readable TOML file with
        ``robots`` (the single spec's loader then reports what is wrong).

    Raises
    ------
    SpecError
        A fleet whose validation fails (exit code 2).
    """
    from ..spec.fleet import is_fleet, load_fleet
    name = args.spec
    if name in bundled_fleets() and not Path(name).exists():
        return load_fleet(name)
    try:
        doc = tomllib.loads(Path(name).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError):
        return None
    return load_fleet(name) if is_fleet(doc) else None


def _no_figures(args: argparse.Namespace, fleet: Any) -> tuple[int, int]:
    """Refuse the single spec's outputs a fleet does not have (``--export``, ``--log``),
    naming the flag; check ``--plot``'s folder and ``--dims`` before any work. Returns the
    figure's dimensions."""
    from ..errors import SpecError
    from ..runtime.dims import parse_dims
    from .plotting import check_plot_folder
    for flag in ("export", "log"):
        if getattr(args, flag, None):
            raise SpecError(f"--{flag}", "is for a single spec, not a fleet (docs/fleets.md)")
    check_plot_folder(args)
    return parse_dims(getattr(args, "dims", None), fleet.robots[0].spec.dimension)


def _plot(args: argparse.Namespace, designed: Any, run: Any, dims: tuple[int, int]) -> None:
    """With ``--plot``: the fleet in time slices (:func:`stt_codegen.plot_fleet`)."""
    from ..runtime.fleet_plots import plot_fleet
    from .plotting import write_plot
    write_plot(args, lambda path: plot_fleet(designed, path, run, dims=dims))


def _designed(fleet: Any) -> Any:
    from ..design.fleet import design_fleet
    return design_fleet(fleet)


def _pair_json(p: Any) -> dict[str, Any]:
    from ..verification.fleet import pair_json
    return pair_json(p)


def fleet_design(args: argparse.Namespace, fleet: Any) -> int:
    """``design FLEET``: every robot's tube and every pair's certified separation.

    Parameters
    ----------
    args : argparse.Namespace
        ``json``, ``plot`` (a PNG of the fleet in time slices), ``dims``.
    fleet : FleetSpec

    Returns
    -------
    int
        0 designed and certified.

    Raises
    ------
    DesignError
        No certified fleet design (exit code 1).
    """
    dims = _no_figures(args, fleet)
    designed = _designed(fleet)
    _plot(args, designed, None, dims)
    if args.json:
        print_json({"fleet": fleet.name, "certified": designed.certified,
                    "order": list(designed.order), "reordered": list(designed.reordered),
                    "design_time_s": designed.design_time_s,
                    "robots": {name: d.to_json() for name, d in designed.designs.items()},
                    "pairs": [_pair_json(p) for p in designed.pairs]})
        return 0
    print(designed.summary())
    for p in designed.pairs:
        print(f"  {'PASS' if p.passed else 'FAIL'}  {p.detail}")
    return 0


def fleet_generate(args: argparse.Namespace, fleet: Any) -> int:
    """``generate FLEET -o DIR``: a folder per robot, ``DIR/<robot>``.

    Parameters
    ----------
    args : argparse.Namespace
        ``out_dir``, ``languages``, ``precision``.
    fleet : FleetSpec

    Returns
    -------
    int
        0 written.

    Raises
    ------
    DesignError
        No certified fleet design (exit code 1).
    """
    from ..codegen.fleet import generate_fleet
    from ..codegen.options import parse_options
    parse_options(args.languages, args.precision)   # bad options fail before the design
    written = generate_fleet(_designed(fleet), Path(args.out_dir), languages=args.languages,
                             precision=args.precision)
    for name, files in written.items():
        print(f"wrote {len(files)} files for {name} into {Path(args.out_dir) / name}")
    print(f"{len(written)} robots of {fleet.name} ({args.languages}, {args.precision}): one "
          "folder each, no shared state")
    return 0


def fleet_simulate(args: argparse.Namespace, fleet: Any, header: str,
                   line: Callable[[Any], str]) -> int:
    """``simulate FLEET``: every robot's closed loop, every pair's closest approach.

    Parameters
    ----------
    args : argparse.Namespace
        ``backend``, ``horizon``, ``seed``, ``json``, ``plot`` (a PNG of the fleet in
        time slices with each body in the run), ``dims``.
    fleet : FleetSpec
    header : str
        The header of the robots' table (``simulate``'s).
    line : callable
        A robot's row of that table, from its ``SimulationResult`` (``simulate``'s).

    Returns
    -------
    int
        0 every robot satisfied and no two bodies closer than their reaches, else 1.

    Raises
    ------
    DesignError
        No certified fleet design (exit code 1).
    """
    from ..runtime.fleet import simulate_fleet
    from .common import checked_seed
    seed = checked_seed(args)
    dims = _no_figures(args, fleet)
    designed = _designed(fleet)
    run = simulate_fleet(designed, backend=args.backend, horizon=args.horizon, seed=seed)
    _plot(args, designed, run, dims)
    if args.json:
        print_json({"fleet": fleet.name, "satisfied": run.satisfied, "horizon": run.horizon,
                    "robots": {n: r.to_json() for n, r in run.results.items()},
                    "approaches": [{"pair": list(a.pair), "clearance": a.clearance,
                                    "t": a.t} for a in run.approaches]})
        return 0 if run.satisfied else 1
    print(header)
    for result in run.results.values():
        print(line(result))
    for a in run.approaches:
        print(f"  {a.pair[0]} and {a.pair[1]}: closest approach {a.clearance:.3f} "
              f"(bodies, at t = {a.t:.3f} s)")
    closest = run.closest
    print(f"fleet {fleet.name}: {'satisfied' if run.satisfied else 'NOT satisfied'}, "
          f"{len(run.results)} robots over {run.horizon:g} s"
          + ("" if closest is None else f", closest approach {closest.clearance:.3f} "
             f"({closest.pair[0]} and {closest.pair[1]} at {closest.t:.3f} s)"))
    return 0 if run.satisfied else 1


def fleet_verify(args: argparse.Namespace, fleet: Any) -> int:
    """``verify FLEET``: every robot's checks and every pair certified again.

    Parameters
    ----------
    args : argparse.Namespace
        ``json``, ``all``, ``quiet``, ``no_cache``; ``plant`` must be ``None`` (each robot
        has its own).
    fleet : FleetSpec

    Returns
    -------
    int
        0 every check passed, 1 a check failed.

    Raises
    ------
    SpecError
        ``--plant`` given (exit code 2).
    DesignError
        No certified fleet design (exit code 1).
    """
    from ..errors import SpecError
    from ..verification.fleet import verify_fleet
    from .common import progress_bar
    if getattr(args, "plant", None) is not None:
        raise SpecError("--plant", "is for a single spec: each robot of a fleet has its own "
                                   "plant (docs/fleets.md)")
    designed = _designed(fleet)
    with progress_bar(args, "verify") as progress:
        report = verify_fleet(designed, progress=progress, cache=not args.no_cache)
    if args.json:
        print_json(report.to_json())
    else:
        print(str(report) if args.all else report.summary())
    return 0 if report.passed else 1
