"""``stt-codegen simulate SPEC``: design the tube, run the closed loop, judge Definition 2.1."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import SpecError
from .common import (add_backend_argument, add_json_argument, add_seed_argument,
                     add_spec_argument, checked_seed, closed_loop, print_json)
from .plotting import add_plot_argument, design_to_plot, write_plot

if TYPE_CHECKING:
    from ..spec.loader import Spec

__all__ = ["SUMMARY_HEADER", "cmd_simulate", "configure_simulate", "summary_line"]

#: Header of the table of :func:`summary_line` rows (``simulate`` and ``demo``).
SUMMARY_HEADER = f"{'case':<22} {'satisfied':<9} {'reach [s]':>9} {'clearance':>9}   max |u|"


def summary_line(result) -> str:
    """One row of the summary table: case, satisfied, reach time, clearance, max ``|u|``.

    Parameters
    ----------
    result : SimulationResult
        One closed-loop run.

    Returns
    -------
    str
        The row, aligned under :data:`SUMMARY_HEADER`.
    """
    clearance = ("-" if result.min_obstacle_clearance is None
                 else f"{result.min_obstacle_clearance:.3f}")
    reach = "-" if result.reach_time is None else f"{result.reach_time:.3f}"
    u_max = ", ".join(f"{v:.3g}" for v in result.max_abs_u)
    return (f"{result.spec:<22} {'yes' if result.satisfied else 'NO':<9} {reach:>9} "
            f"{clearance:>9}   [{u_max}]")


def cmd_simulate(args: argparse.Namespace) -> int:
    """0 satisfied, 1 not satisfied or no design, 2 bad input, 3 toolchain.

    Parameters
    ----------
    args : argparse.Namespace
        ``spec``, ``backend``, ``horizon`` (s, or ``None`` for ``t_c``), ``seed``, ``plot``,
        ``dims``, ``log`` (an MCAP path or ``None``), ``sensed`` (a file of the obstacles a
        spec with ``[sensing]`` meets, or ``None``: a bundled case's own people, else none;
        :mod:`~stt_codegen.runtime.walking_file`) and ``json``.

    Returns
    -------
    int
        0 the task is satisfied, 1 it is not.

    Raises
    ------
    SpecError
        A bad spec, ``--seed``, ``--horizon``, ``--plot`` folder, ``--dims``, ``--log``
        (not ``.mcap``, a missing folder, ``mcap-ros2-support`` not installed) or
        ``--sensed`` (unreadable, a bad entry, off the spec's sensing dimensions, a spec
        without ``[sensing]`` or a fleet), exit code 2, before any work.
    DesignError
        No design (exit code 1).
    ToolchainError
        The backend's compiler is missing or fails (exit code 3).
    """
    from .fleet import fleet_simulate, fleet_of
    fleet = fleet_of(args)            # a fleet file: one design per robot (docs/fleets.md)
    if fleet is not None:
        if args.sensed is not None:
            raise SpecError("sensed", "a fleet's robots sense no obstacles at run time "
                                      "(docs/fleets.md); --sensed takes a spec with "
                                      "[sensing]")
        return fleet_simulate(args, fleet, SUMMARY_HEADER, summary_line)
    from ..runtime.run_log import check_log_path, write_run_log
    seed = checked_seed(args)
    if args.log is not None:
        check_log_path(args.log)
    sensed = _SensedObstacles(args)
    design, dims = design_to_plot(args, sensed.check)
    result = closed_loop(design, lambda: sensed.obstacles, args.backend, args.horizon, seed)
    if args.log is not None:
        write_run_log(design, result, args.log)

    def draw(path):
        from ..runtime.plots import plot_run
        return plot_run(design, result, path, dims=dims)
    write_plot(args, draw)
    if args.json:
        data = result.to_json()
        data["design"] = design.to_json()
        if result.sensing is not None:
            data["sensed_obstacles"] = {"count": len(sensed.obstacles), "source": sensed.kind}
        print_json(data)
    else:
        print(SUMMARY_HEADER)
        print(summary_line(result))
        print(f"backend {result.backend}, {result.steps} steps at {design.tube.rate_hz:g} Hz, "
              f"t_c = {result.prescribed_time:g} s, "
              + (f"gain k = {design.gain:.4g}, " if result.stayed_in_velocity_tube is None
                 else "cascade law, stayed in velocity tube: "
                 f"{'yes' if result.stayed_in_velocity_tube else 'NO'}, ") +
              f"stayed in tube: {'yes' if result.stayed_in_tube else 'NO'}, "
              f"collision: {'YES' if result.collision else 'no'}, "
              f"left state space: {'YES' if result.left_state_space else 'no'}")
        if design.spec.mujoco is not None:        # MuJoCo's own contacts
            first = ("" if result.first_contact is None else
                     f", first at {result.first_contact[0]:g} s ({result.first_contact[1]} - "
                     f"{result.first_contact[2]})")
            print(f"MuJoCo contacts (other than with the ground): {result.contacts} "
                  f"timesteps{first}")
        if result.sensing is not None:            # [sensing]
            print(f"sensed obstacles: {len(sensed.obstacles)} ({sensed.source}); "
                  f"{result.sensing.summary()}")
        for task in result.tasks:                 # [[tasks]]
            when = "" if task.time is None else f" at {task.time:g} s"
            print(f"task {task.task} {task.kind} [{task.window[0]:g}, {task.window[1]:g}] s: "
                  f"{'met' if task.met else 'NOT met'}"
                  f"{when if task.kind == 'reach' or not task.met else ''}, margin "
                  f"{'-' if task.margin is None else f'{task.margin:.3g}'}")
        if args.plot:
            print(f"plot written to {args.plot}")
        if args.log is not None:
            print(f"run written to {args.log} (ROS 2 messages, docs/cli.md)")
    return 0 if result.satisfied else 1


class _SensedObstacles:
    """The obstacles a spec with ``[sensing]`` is run among: ``--sensed FILE``'s, else a
    bundled case's own people, else none; checked against the spec before the design."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.file = None
        if args.sensed is not None:            # read before any work
            from ..runtime.walking_file import load_walking_obstacles
            self.file = load_walking_obstacles(args.sensed)
        self.obstacles: tuple = ()
        #: where they come from: "file", "case" or "none"
        self.kind = "none"

    @property
    def source(self) -> str:
        """Where they come from, in words."""
        return {"file": f"from {self.args.sensed}", "case": "the case's own people",
                "none": "none given: --sensed FILE lists them, docs/sensing.md"}[self.kind]

    def check(self, spec: Spec) -> None:
        """Refuse ``--sensed`` for a spec without ``[sensing]``, or obstacles off its
        sensing dimensions; choose the obstacles."""
        from ..runtime.sensed import PEOPLE_CASES, bundled_people, check_walking
        if self.file is not None:
            try:
                check_walking(self.file, spec, "walking_obstacles")
            except SpecError as exc:        # a spec without [sensing]: the flag's fault
                raise SpecError("sensed" if exc.field == "sensing" else exc.field,
                                exc.reason) from None
            self.obstacles, self.kind = self.file, "file"
        elif spec.sensing is not None and spec.name in PEOPLE_CASES \
                and not Path(self.args.spec).exists():
            self.obstacles, self.kind = bundled_people(spec.name), "case"


def configure_simulate(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen simulate``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``SPEC``, ``--backend``, ``--horizon``, ``--seed``,
        ``--plot``, ``--dims``, ``--log``, ``--sensed``, ``--json`` and the ``handler``
        :func:`cmd_simulate`.
    """
    add_spec_argument(p)
    add_backend_argument(p)
    p.add_argument("--horizon", type=float, default=None, metavar="S",
                   help="simulated time in seconds (default: t_c)")
    add_seed_argument(p)
    add_plot_argument(p, "the run")
    p.add_argument("--log", metavar="RUN.mcap", default=None,
                   help="write the run as ROS 2 messages to an MCAP file (Foxglove, ros2 bag "
                        "play; the optional extra ros)")
    p.add_argument("--sensed", metavar="FILE", default=None,
                   help="obstacles a spec with [sensing] meets at run time, unknown to its "
                        "design: a TOML file of [[walking_obstacles]] (docs/sensing.md; "
                        "default: a bundled case's own people, else none)")
    add_json_argument(p)
    p.set_defaults(handler=cmd_simulate)
