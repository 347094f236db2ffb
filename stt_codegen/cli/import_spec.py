"""``stt-codegen import pointmaze NAME -o SPEC``: a spec from another tool's task."""

from __future__ import annotations

import argparse

__all__ = ["cmd_import_pointmaze", "configure_import"]


def cmd_import_pointmaze(args: argparse.Namespace) -> int:
    """Write the spec (and ``--mjcf``, the MuJoCo model) of a PointMaze maze; exit 0.

    Parameters
    ----------
    args : argparse.Namespace
        ``name``, ``path``, ``start``, ``goal``, ``prescribed_time``, ``rate_hz``,
        ``contact_margin``, ``model`` and ``mjcf``.

    Returns
    -------
    int
        0 written.

    Raises
    ------
    SpecError
        gymnasium-robotics missing, an unknown map, a bad cell or value, an output folder
        that does not exist (exit code 2; nothing written).
    """
    from ..pointmaze import import_pointmaze
    doc = import_pointmaze(args.name, args.path, start=args.start, goal=args.goal,
                           prescribed_time=args.prescribed_time, rate_hz=args.rate_hz,
                           contact_margin=args.contact_margin, model=args.model,
                           mjcf=args.mjcf)
    print(f"{doc['name']}: {len(doc['obstacles'])} wall boxes, robot radius "
          f"{doc['robot']['radius']:g} m, t_c = {doc['prescribed_time']:g} s, written to "
          f"{args.path}" + (f" (MuJoCo model: {args.mjcf})" if args.mjcf else ""))
    return 0


def configure_import(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen import`` and its one source, ``pointmaze``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; its ``pointmaze`` subcommand gets ``NAME``, ``-o``,
        ``--start``, ``--goal``, ``--prescribed-time``, ``--rate-hz``,
        ``--contact-margin``, ``--model``, ``--mjcf`` and the ``handler``
        :func:`cmd_import_pointmaze`.
    """
    from ..pointmaze import DEFAULT_CONTACT_MARGIN, DEFAULT_RATE_HZ, SECONDS_PER_CELL
    p.description = "Write a spec from another tool's task."
    sub = p.add_subparsers(dest="import_source", required=True, metavar="SOURCE")
    q = sub.add_parser("pointmaze", help="a maze of gymnasium-robotics' PointMaze "
                                         '(pip install ".[mujoco]")')
    q.add_argument("name", metavar="NAME", help="the map as gymnasium-robotics spells it "
                                                "(UMaze, Medium, Large, Large_Diverse_G...)")
    q.add_argument("-o", "--output", dest="path", required=True, metavar="SPEC",
                   help="the spec file to write (TOML)")
    q.add_argument("--start", metavar="ROW,COL", default=None,
                   help="the start cell (default: the map's reset cell, else its first "
                        "free cell)")
    q.add_argument("--goal", metavar="ROW,COL", default=None,
                   help="the goal cell (default: the map's goal cell farthest from the start)")
    q.add_argument("--prescribed-time", type=float, default=None, metavar="S",
                   help=f"t_c in s (default: {SECONDS_PER_CELL:g} s per cell of the path)")
    q.add_argument("--rate-hz", type=float, default=DEFAULT_RATE_HZ, metavar="HZ",
                   help=f"controller rate (default: {DEFAULT_RATE_HZ:g})")
    q.add_argument("--contact-margin", type=float, default=DEFAULT_CONTACT_MARGIN,
                   metavar="M", help="added to the ball's radius, m (default: "
                                     f"{DEFAULT_CONTACT_MARGIN:g})")
    q.add_argument("--model", default="single-integrator",
                   help="plant.model (default: single-integrator)")
    q.add_argument("--mjcf", default=None, metavar="XML",
                   help="also write the maze's MuJoCo model (gymnasium-robotics' builder)")
    q.set_defaults(handler=cmd_import_pointmaze)
