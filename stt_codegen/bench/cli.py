"""The ``bench`` subcommand and its sub-subcommands ``arenas``, ``step``, ``scaling``,
``covering`` and ``alpha``."""

from __future__ import annotations

import argparse


def _non_negative_int(text: str) -> int:
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be non-negative, got {value}")
    return value


def _cmd_arenas(args: argparse.Namespace) -> int:
    from .arenas_bench import main_arenas
    return main_arenas(args)


def _cmd_step(args: argparse.Namespace) -> int:
    from .step import main_step
    return main_step(args)


def _cmd_scaling(args: argparse.Namespace) -> int:
    from .scaling import main_scaling
    return main_scaling(args)


def _cmd_covering(args: argparse.Namespace) -> int:
    from .covering import main_covering
    return main_covering(args)


def _cmd_alpha(args: argparse.Namespace) -> int:
    from .alpha import main_alpha
    return main_alpha(args)


def configure_bench(bench: argparse.ArgumentParser) -> None:
    """Sub-subcommands ``bench arenas``, ``step``, ``scaling``, ``covering`` and ``alpha``."""
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
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_cmd_arenas)

    p = sub.add_parser("step", help="cost of one controller step: reference, CasADi, "
                                    "generated Python, generated C")
    p.add_argument("spec", metavar="SPEC", help="bundled case name or spec file")
    p.add_argument("--steps", type=int, default=None, metavar="N",
                   help="C steps per timed run (default: 100000)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_cmd_step)

    p = sub.add_parser("scaling", help="code size, generation time and step cost vs "
                                       "obstacles and state dimension")
    p.add_argument("--obstacles", default="1,10,100,1000", metavar="LIST",
                   help="obstacle counts (default: %(default)s)")
    p.add_argument("--dimensions", default="2,3,6,12", metavar="LIST",
                   help="state dimensions (default: %(default)s)")
    p.add_argument("--compile-timeout", type=float, default=900.0, metavar="S",
                   help="give up compiling one design after S seconds (default: %(default)s)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_cmd_scaling)

    p = sub.add_parser("covering", help="covering random polygons by boxes, and the design "
                                        "around them: boxes and seconds")
    p.add_argument("--count", type=int, default=80, help="polygons (default: %(default)s)")
    p.add_argument("--seed", type=_non_negative_int, default=0,
                   help="polygon seed (default: %(default)s)")
    p.add_argument("--tolerance", type=float, default=0.02, metavar="M",
                   help="covering tolerance of every polygon (default: %(default)s)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_cmd_covering)

    p = sub.add_parser("alpha", help="the implicit alpha step: Newton iterations against "
                                     "bisection, and convergence to a stiff solver")
    p.add_argument("spec", metavar="SPEC", nargs="?", default="omnirobot-s1",
                   help="bundled case name or spec file (default: %(default)s)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_cmd_alpha)
