"""``stt-codegen bench arenas | tasks | drive | agv | step | scaling | covering | alpha | second-order |
stl | sampled | overhead | delay | fleet | sensed``: the benchmarks and studies of :mod:`stt_codegen_bench`."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from pathlib import Path

from stt_codegen.errors import SpecError
from stt_codegen.spec.plants import plant_entry
from stt_codegen.cli.common import add_json_argument, add_spec_argument

__all__ = ["configure_bench"]


def _non_negative_int(text: str) -> int:
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be non-negative, got {value}")
    return value


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def _positive_float(text: str) -> float:
    value = float(text)
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"must be positive and finite, got {value}")
    return value


def _int_list(text: str, field: str) -> list[int]:
    """``"1,10,100"`` as ``[1, 10, 100]``; :class:`SpecError` naming ``field`` otherwise."""
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise SpecError(field, f"expected a comma-separated list of integers, got {text!r}") from None
    if not values:
        raise SpecError(field, "empty list")
    return values


def _cmd_arenas(args: argparse.Namespace) -> int:
    if plant_entry(args.plant).order == 2:    # the cascade beside A* + tracker
        from .second_order_arenas import (format_double_integrator_report,
                                                 run_double_integrator_bench)
        report = run_double_integrator_bench(args.count, args.seed)
        print(json.dumps(report, indent=1, sort_keys=True) if args.json
              else format_double_integrator_report(report))
        return 0
    from .arenas_bench import format_arenas_report, run_arenas_bench, write_specs
    if args.specs:
        write_specs(Path(args.specs), args.count, args.seed)
    report = run_arenas_bench(args.count, args.seed, workers=args.workers,
                              scheduler=args.scheduler,
                              methods=tuple(args.methods.split(",")) if args.methods else None,
                              progress=not args.no_progress)
    print(json.dumps(report, indent=1, sort_keys=True, allow_nan=False) if args.json
          else format_arenas_report(report))
    return 0


def _office_bench() -> tuple[Callable[[int, int], dict], Callable[[dict], str]]:
    from .office_arenas import format_office_report, run_office_bench
    return run_office_bench, format_office_report


def _agv_bench() -> tuple[Callable[[int, int], dict], Callable[[dict], str]]:
    from .agv import format_agv_report, run_agv_bench
    return run_agv_bench, format_agv_report


def _add_seeded(sub, name: str, help_text: str, what: str, count: int,
                bench: Callable[[], tuple[Callable[[int, int], dict],
                                          Callable[[dict], str]]]) -> None:
    """A bench of ``--count`` problems of ``--seed``: ``bench()`` gives its ``run(count,
    seed) -> report`` and ``format(report) -> str`` (imported when it runs); the report is
    printed as its table or, with ``--json``, as JSON."""
    p = sub.add_parser(name, help=help_text)
    p.add_argument("--count", type=int, default=count,
                   help=f"number of {what}s (default: {count})")
    p.add_argument("--seed", type=_non_negative_int, default=0,
                   help=f"{what} seed (default: 0)")
    add_json_argument(p)

    def handler(args: argparse.Namespace) -> int:
        run, fmt = bench()
        report = run(args.count, args.seed)
        print(json.dumps(report, indent=1, sort_keys=True) if args.json else fmt(report))
        return 0

    p.set_defaults(handler=handler)


def _cmd_step(args: argparse.Namespace) -> int:
    from .step import format_step_report, run_step_bench
    report = run_step_bench(args.spec, steps=args.steps)
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_step_report(report))
    return 0


def _cmd_scaling(args: argparse.Namespace) -> int:
    from .scaling import format_scaling_report, run_scaling_bench
    report = run_scaling_bench(_int_list(args.obstacles, "obstacles"),
                               _int_list(args.dimensions, "dimensions"),
                               compile_timeout=args.compile_timeout)
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_scaling_report(report))
    return 0


def _cmd_covering(args: argparse.Namespace) -> int:
    from .covering import format_covering_report, run_covering_bench
    report = run_covering_bench(args.seed, args.count, args.tolerance)
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_covering_report(report))
    return 0


def _cmd_alpha(args: argparse.Namespace) -> int:
    from .alpha import format_alpha_report, run_alpha_bench
    report = run_alpha_bench(args.spec)
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_alpha_report(report))
    return 0


def _cmd_tasks(args: argparse.Namespace) -> int:
    from .tasks_bench import format_tasks_report, run_tasks_bench
    report = run_tasks_bench(args.count, args.seed, progress=not args.no_progress)
    print(json.dumps(report, indent=1, sort_keys=True, allow_nan=False) if args.json
          else format_tasks_report(report))
    return 0


def _cmd_second_order(args: argparse.Namespace) -> int:
    from .second_order_study import format_second_order_report, run_second_order_study
    report = run_second_order_study(args.spec, args.count, args.seed, spread=args.spread,
                                    corners=args.corners, adversary=args.adversary)
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_second_order_report(report))
    return 0


def _cmd_stl(args: argparse.Namespace) -> int:
    from .stl_bench import format_stl_report, run_stl_bench
    names = [n.strip() for n in args.scenarios.split(",") if n.strip()] if args.scenarios \
        else None
    report = run_stl_bench(names, horizon=args.horizon,
                           solver=None if args.solver == "none" else args.solver,
                           specs=Path(args.specs) if args.specs else None,
                           orders={"both": ("first", "second")}.get(args.order,
                                                                    (args.order,)),
                           disturbance=args.disturbance)
    if args.json:
        report = {"rows": [{k: v for k, v in row.items() if k != "spec"}
                           for row in report["rows"]], "order_note": report["order_note"]}
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_stl_report(report))
    return 0


def _cmd_overhead(args: argparse.Namespace) -> int:
    from .overhead import format_overhead_report, run_overhead_bench
    commands = tuple(c.strip() for c in args.commands.split(",") if c.strip())
    try:
        report = run_overhead_bench(args.spec, commands, runs=args.runs)
    except ValueError as exc:
        raise SpecError("commands", str(exc)) from None
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_overhead_report(report))
    return 0


def _cmd_sampled(args: argparse.Namespace) -> int:
    from .sampled_bench import DEFAULT_SPECS, format_sampled_report, run_sampled_bench
    specs = (tuple(s.strip() for s in args.specs.split(",") if s.strip()) if args.specs
             else DEFAULT_SPECS)
    if not 0.0 <= args.delay <= 1.0:
        raise SpecError("--delay", f"must be a fraction of the period in [0, 1], got "
                                   f"{args.delay:g}")
    report = run_sampled_bench(specs, runs=args.runs, delay=args.delay)
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_sampled_report(report))
    return 0


def _cmd_delay(args: argparse.Namespace) -> int:
    from .delay_bench import format_delay_report, run_delay_bench
    report = run_delay_bench()
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_delay_report(report))
    return 0


def _cmd_fleet(args: argparse.Namespace) -> int:
    from .fleet_bench import format_fleet_report, run_fleet_bench
    report = run_fleet_bench(args.count, args.seed, robots=args.robots, simulate=args.simulate,
                             workers=args.workers, scheduler=args.scheduler, first=args.first)
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_fleet_report(report))
    return 0


def _cmd_sensed(args: argparse.Namespace) -> int:
    from .sensed_bench import format_sensed_report, run_sensed_bench
    report = run_sensed_bench(args.count, args.seed,
                              tuple(_int_list(args.obstacles, "--obstacles")),
                              adversary=args.adversary, acceleration=args.acceleration,
                              speed_only=args.speed_only, warehouse=args.warehouse,
                              script=args.script, rooms=args.rooms)
    if args.cortex_m4f:
        from .sensed_bench import target_costs
        report["cortex_m4f"] = target_costs(args.acceleration, warehouse=args.warehouse,
                                            script=args.script, rooms=args.rooms)
    print(json.dumps(report, indent=1, sort_keys=True) if args.json
          else format_sensed_report(report))
    return 0


def configure_bench(bench: argparse.ArgumentParser) -> None:
    """Sub-subcommands ``bench arenas``, ``tasks``, ``drive``, ``agv``, ``step``, ``scaling``,
    ``covering``, ``alpha``, ``second-order``, ``stl``, ``sampled``, ``overhead``, ``delay``,
    ``fleet`` and ``sensed``.

    Parameters
    ----------
    bench : argparse.ArgumentParser
        The parser of ``stt-codegen bench``; its sub-subcommands are added to it, each with its
        ``handler``.
    """
    bench.description = ("Benchmarks. Every comparison is measured side by side in one run on "
                         "this machine; ratios, not absolute times, are the result.")
    sub = bench.add_subparsers(dest="bench_command", required=True, metavar="BENCH")

    p = sub.add_parser("arenas", help="STT vs A* and RRT* (plus a tracker) on random arenas")
    p.add_argument("--count", type=int, default=100, help="number of arenas (default: 100)")
    p.add_argument("--seed", type=_non_negative_int, default=0, help="arena seed (default: 0)")
    p.add_argument("--workers", type=int, default=None, metavar="W",
                   help="local worker processes (default: the usable CPUs)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on an existing Dask distributed scheduler instead")
    p.add_argument("--methods", default=None, metavar="LIST",
                   help="comma-separated subset of stt,astar,rrtstar (default: all available)")
    p.add_argument("--specs", default=None, metavar="DIR",
                   help="also write the arenas as spec files into DIR")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--plant", choices=("single-integrator", "double-integrator"),
                   default="single-integrator",
                   help="double-integrator: the cascade law (docs/second-order.md) beside "
                        "A* + a velocity-loop tracker, sequentially (default: %(default)s)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_arenas)

    p = sub.add_parser("tasks", help="timed reach tasks: STT vs sequential A* with waiting "
                                     "(plus the tracker) on random problems")
    p.add_argument("--count", type=int, default=20, help="number of problems (default: 20)")
    p.add_argument("--seed", type=_non_negative_int, default=0,
                   help="problem seed (default: 0)")
    p.add_argument("--no-progress", action="store_true", help="no line per problem")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_tasks)

    _add_seeded(sub, "drive", "a differential-drive base beside a holonomic one on random "
                "offices (docs/differential-drive.md)", "office", 100, _office_bench)
    _add_seeded(sub, "agv", "a warehouse AGV's reach time against the straight-line time "
                "at v_max along its route, on seeded floors", "floor", 5, _agv_bench)

    p = sub.add_parser("step", help="cost of one controller step: reference, CasADi, "
                                    "generated Python, generated C")
    add_spec_argument(p)
    p.add_argument("--steps", type=int, default=None, metavar="N",
                   help="C steps per timed run (default: 100000)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_step)

    p = sub.add_parser("scaling", help="code size, generation time and step cost vs "
                                       "obstacles and state dimension")
    p.add_argument("--obstacles", default="1,10,100,1000", metavar="LIST",
                   help="obstacle counts (default: %(default)s)")
    p.add_argument("--dimensions", default="2,3,6,12", metavar="LIST",
                   help="state dimensions (default: %(default)s)")
    p.add_argument("--compile-timeout", type=float, default=900.0, metavar="S",
                   help="give up compiling one design after S seconds (default: %(default)s)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_scaling)

    p = sub.add_parser("covering", help="covering random polygons by boxes, and the design "
                                        "around them: boxes and seconds")
    p.add_argument("--count", type=int, default=80, help="polygons (default: %(default)s)")
    p.add_argument("--seed", type=_non_negative_int, default=0,
                   help="polygon seed (default: %(default)s)")
    p.add_argument("--tolerance", type=float, default=0.02, metavar="M",
                   help="covering tolerance of every polygon (default: %(default)s)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_covering)

    p = sub.add_parser("alpha", help="the implicit alpha step: Newton iterations against "
                                     "bisection, and convergence to a stiff solver")
    p.add_argument("spec", metavar="SPEC", nargs="?", default="omnirobot-s1",
                   help="bundled case name or spec file (default: %(default)s)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_alpha)

    p = sub.add_parser("second-order", help="the cascade law on random second-order plants "
                                            "within a case's declared bounds")
    p.add_argument("spec", metavar="SPEC", nargs="?", default="second-order-s1",
                   help="bundled case or spec file with a second-order plant.model "
                        "(default: %(default)s)")
    p.add_argument("--count", type=int, default=300, help="plants (default: %(default)s)")
    p.add_argument("--seed", type=_non_negative_int, default=0, help="seed (default: 0)")
    p.add_argument("--spread", type=float, default=1.0, metavar="F",
                   help="draw plants F times beyond the declared bounds (default: 1, within)")
    p.add_argument("--corners", action="store_true",
                   help="plants at the corners of the declared bounds, with the largest "
                        "disturbance")
    p.add_argument("--adversary", action="store_true",
                   help="also search the certified class for a member that leaves a tube "
                        "(extreme members switched per sampling interval)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_second_order)

    p = sub.add_parser("stl", help="stlpy's benchmark scenarios written as specs, designed, "
                                   "run with the generated C and judged by rtamt "
                                   '(pip install ".[stl]")')
    p.add_argument("--scenarios", default=None, metavar="LIST",
                   help="comma-separated subset of ReachAvoid, EitherOr, NarrowPassage, "
                        "RandomMultitarget, DoorPuzzle, NonlinearReachAvoid, SteppingStones "
                        "(default: all)")
    p.add_argument("--horizon", type=int, default=None, metavar="T",
                   help="stlpy's horizon T in steps for every scenario (default: each "
                        "example's)")
    p.add_argument("--solver", choices=("scipy", "drake-bnb", "none"), default="scipy",
                   help="stlpy's solver run beside: scipy (ScipyGradientSolver), drake-bnb "
                        "(DrakeMICPSolver with Drake's branch and bound; pip install drake) "
                        "or none (default: %(default)s)")
    p.add_argument("--specs", default=None, metavar="DIR",
                   help="also write the specs into DIR")
    p.add_argument("--order", choices=("first", "second", "both"), default="both",
                   help="a double integrator as the first-order position law (its input the "
                        "velocity), as itself (the cascade, the example's |u| and |v|), or "
                        "both (default: %(default)s)")
    p.add_argument("--disturbance", type=float, default=None, metavar="W",
                   help="plant.disturbance_amplitude of every spec written: 0 is stlpy's "
                        "model, which has none (default: the project's, 0.1)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_stl)

    p = sub.add_parser("delay", help="the computation delay law (13) is proved to tolerate, "
                                     "plain and with the delay-compensating prediction")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_delay)

    p = sub.add_parser("sampled", help="law (13)'s per-axis sampled check: the folded step "
                                       "beside the Python loop it is tested against")
    p.add_argument("--specs", default=None, metavar="LIST",
                   help="comma-separated bundled cases or spec files (default: "
                        "omnirobot-s3, crossing-moving, omnirobot-s1, office-base)")
    p.add_argument("--runs", type=_positive_int, default=3, metavar="N",
                   help="runs of each, the least CPU kept (default: %(default)s)")
    p.add_argument("--delay", type=float, default=0.0, metavar="FRACTION",
                   help="a computation delay, as a fraction of the period (default: none)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_sampled)

    p = sub.add_parser("overhead", help="CPU of a command beside the library call it makes "
                                        "(stt-codegen design SPEC against design_tube)")
    p.add_argument("spec", metavar="SPEC", nargs="?", default="omnirobot-s1",
                   help="bundled case name or spec file (default: %(default)s)")
    p.add_argument("--commands", default="design", metavar="LIST",
                   help="comma-separated subset of design, generate, verify "
                        "(default: %(default)s)")
    p.add_argument("--runs", type=_positive_int, default=5, metavar="N",
                   help="runs of each measurement, the least CPU kept (default: 5)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_overhead)

    p = sub.add_parser("fleet", help="prioritized fleet design on seeded warehouse floors: "
                                     "certified fraction, design time beside the robots "
                                     "designed alone (docs/fleets.md)")
    p.add_argument("--robots", type=_positive_int, default=8, metavar="N",
                   help="robots per floor (default: %(default)s)")
    p.add_argument("--count", type=_positive_int, default=5, help="number of floors "
                                                                  "(default: %(default)s)")
    p.add_argument("--seed", type=_non_negative_int, default=0,
                   help="floor seed (default: 0)")
    p.add_argument("--first", type=_non_negative_int, default=0, metavar="K",
                   help="the first floor's index: floors K to K + count - 1 (default: 0)")
    p.add_argument("--simulate", action="store_true",
                   help="also run every robot's generated C in closed loop (the closest "
                        "approach)")
    p.add_argument("--workers", type=_positive_int, default=1, metavar="W",
                   help="floors designed in W local processes at once; each floor's CPU "
                        "time is its own process's (default: 1, in turn)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the floors on an existing Dask distributed scheduler instead")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_fleet)

    p = sub.add_parser("sensed", help="obstacles sensed at run time: Real-Time STT's 2-D "
                                      "scenario (moving circles), replanning within the "
                                      "envelope (docs/sensing.md)")
    p.add_argument("--count", type=_positive_int, default=10,
                   help="episodes per obstacle count (default: %(default)s)")
    p.add_argument("--seed", type=_non_negative_int, default=0,
                   help="episode seed (default: 0)")
    p.add_argument("--obstacles", default="5,20", metavar="LIST",
                   help="comma-separated obstacle counts (default: %(default)s)")
    p.add_argument("--adversary", action="store_true",
                   help="add a circle heading for the robot at the envelope's speed")
    p.add_argument("--acceleration", type=_positive_float, default=None, metavar="A",
                   help="the envelope's max_obstacle_acceleration, m/s^2 (with velocity_error "
                        "0.05 m/s): the circles turn back before the walls at A/2 per axis "
                        "instead of bouncing, and the adversary turns at A (default: no "
                        "acceleration bound, bouncing circles)")
    p.add_argument("--speed-only", action="store_true",
                   help="with --acceleration: the same circles and adversary, but the "
                        "envelope without the acceleration bound (reachable sets growing at "
                        "the speed bound), for a side-by-side comparison")
    p.add_argument("--warehouse", action="store_true",
                   help="a warehouse floor (three racks, 20 m x 12 m) with people crossing "
                        "its aisles at up to 1 m/s instead of the circles; --obstacles "
                        "counts people (not with --adversary or --acceleration)")
    p.add_argument("--script", action="store_true",
                   help="Real-Time STT's own 2-D script instead (its arena, start, target and "
                        "five circles at 0.2-0.45 m/s, each episode moving their starts and "
                        "turning their headings); with --adversary the pursuer starts at the "
                        "target; --obstacles 5, not with --warehouse or --acceleration")
    p.add_argument("--rooms", action="store_true",
                   help="a drone's room in 3-D (tests/specs/drone-sensed.toml: 10 x 10 x 4 m, "
                        "balls of radius 0.1-0.5 m flying straight at under 1 m/s) instead; "
                        "--obstacles counts balls (not with --adversary, --acceleration, "
                        "--warehouse or --script)")
    p.add_argument("--cortex-m4f", action="store_true",
                   help="also count the controller's instructions per step and per switch "
                        "on the Cortex-M4F (QEMU), the tube as data, on the scenario's tube "
                        "and on one with 16 windows open (stt-codegen embedded --tube-data)")
    add_json_argument(p)
    p.set_defaults(handler=_cmd_sensed)
