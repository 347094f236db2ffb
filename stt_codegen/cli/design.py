"""``stt-codegen design SPEC``: design and certify the tube only (no simulation)."""

from __future__ import annotations

import argparse
import io
from pathlib import Path

from ..errors import SpecError
from .common import add_json_argument, add_quiet_argument, add_spec_argument, print_json
from .plotting import add_plot_argument, design_to_plot, write_plot

__all__ = ["cmd_design", "configure_design", "export_tube"]

#: What ``--export`` writes, by the file's extension.
EXPORT_FORMATS = (".csv", ".npz")


def _check_export(args: argparse.Namespace) -> None:
    """Refuse an ``--export`` path of another extension or in a missing folder, before
    any work."""
    if args.export is None:
        return
    path = Path(args.export)
    if path.suffix.lower() not in EXPORT_FORMATS:
        raise SpecError("export", f"must end in {' or '.join(EXPORT_FORMATS)} (CSV or NumPy "
                                  f"archive), got {args.export!r}")
    folder = path.parent
    if not folder.is_dir():
        raise SpecError("export", f"folder {str(folder)!r} does not exist")


def export_tube(design, path: str | Path) -> None:
    """Write :meth:`~stt_codegen.design.result.Design.tube_table` to ``path``, atomically:
    CSV (a header row ``t [s],gamma_L_1 [state units],...``, then one row an instant, 17
    significant digits) or a NumPy ``.npz`` archive (one array a column, same names
    without the units).

    Parameters
    ----------
    design : Design
        The certified design.
    path : str or pathlib.Path
        Ends in ``.csv`` or ``.npz``.

    Raises
    ------
    SpecError
        Another extension, or a missing folder (field ``export``).
    """
    import numpy as np
    from ..system import atomic_write
    table = design.tube_table()
    buffer = io.BytesIO()
    if Path(path).suffix.lower() == ".npz":
        np.savez(buffer, **table)
    elif Path(path).suffix.lower() == ".csv":
        header = ",".join(f"{name} [{'s' if name == 't' else 'state units'}]"
                          for name in table)
        np.savetxt(buffer, np.column_stack(list(table.values())), fmt="%.17g",
                   delimiter=",", header=header, comments="")
    else:
        raise SpecError("export", f"must end in {' or '.join(EXPORT_FORMATS)}, got "
                                  f"{str(path)!r}")
    atomic_write(path, buffer.getvalue(), field="export")


def cmd_design(args: argparse.Namespace) -> int:
    """0 designed, 1 no design (``--plot``: the best rejected tube is drawn), 2 bad input.

    Parameters
    ----------
    args : argparse.Namespace
        ``spec``, ``json``, ``quiet``, ``plot``, ``dims`` and ``export`` (a ``.csv``
        or ``.npz`` path for the tube at the controller's rate, :func:`export_tube`).

    Returns
    -------
    int
        0 designed (the design as text, or ``Design.to_json()`` with ``--json``).

    Raises
    ------
    SpecError
        A bad spec, ``--plot`` folder, ``--dims`` or ``--export`` path (exit code 2),
        refused before any work.
    DesignError
        No design (exit code 1).
    """
    from .fleet import fleet_design, fleet_of
    fleet = fleet_of(args)            # a fleet file: one design per robot (docs/fleets.md)
    if fleet is not None:
        return fleet_design(args, fleet)
    _check_export(args)
    design, dims = design_to_plot(args)
    spec = design.spec

    def draw(path):
        from ..runtime.plots import plot_design
        return plot_design(design, path, dims=dims)
    write_plot(args, draw)
    if args.export is not None:
        export_tube(design, args.export)
    if args.json:
        print_json(design.to_json())
        return 0
    tube = design.tube
    print(f"{spec.name}: designed with the {design.method} method in "
          f"{design.design_time_s * 1e3:.1f} ms, gain k = {tube.gain:.4g}, "
          f"{len(tube.segments)} reach segment(s), {len(tube.circumvents)} circumvent(s)")
    if design.motion:                            # moving obstacles: how they are avoided
        print(f"  moving obstacles avoided: {design.motion} (docs/moving-obstacles.md)")
    for c in tube.circumvents:
        print(f"  circumvent obstacle {c.obstacle}: x{c.dimension + 1} {c.side}, window "
              f"[{c.start:.3f}, {c.end:.3f}] s, height {c.height:.3g}, sharpness {c.sharpness:g}")
    for s in tube.segments:
        box = ", ".join(f"[{a:.3g}, {b:.3g}]" for a, b in zip(s.lower_to, s.upper_to))
        print(f"  reach segment {s.profile} [{s.start:.3f}, {s.end:.3f}] s to {box}")
    if spec.sensing is not None:                 # [sensing]
        print(_sensing_line(spec.sensing))
    if design.target_choice is not None:         # [target] any_of
        print(f"  target: any_of[{design.target_choice}]")
        for q, name in spec.target_dropped:
            print(f"  note: target any_of[{q}] meets {name}: dropped")
    plan = design.task_plan
    for k, (task, q) in enumerate(zip(spec.tasks, design.task_choices)):      # [[tasks]]
        which = f" (any_of[{task.any_of_index[q]}])" if len(task.boxes) > 1 else ""
        for i, o in task.dropped:
            print(f"  note: task {task.label} any_of[{i}] meets obstacle {o}: dropped")
        visit = "" if plan is None else (f", visit {plan.order.index(k) + 1}, held over "
                                         f"[{plan.holds[k][0]:.3f}, {plan.holds[k][1]:.3f}] s")
        print(f"  task {task.label} {task.kind} [{task.window[0]:g}, {task.window[1]:g}] s: "
              f"planned through its box{which}{visit}")
    for m in design.certificate.margins:
        print(f"  {'PASS' if m.passed else 'FAIL'}  {m.name}: margin {m.margin:.4g}")
    if design.input_proof is not None and spec.input_bound is not None:    # [actuator]
        from ..spec.variants import variant_of
        law = variant_of(spec).input_words
        unit = f" {spec.input_unit}" if spec.input_unit else ""
        peaks = ", ".join(f"|{name}| {p:.4g} <= {b:g}{unit}" for name, p, b in zip(
            spec.input_names, design.input_proof.peak, spec.input_bound))
        if spec.reverse_speed is not None:
            peaks += (f", backing up {design.input_proof.backward:.4g} <= "
                      f"{spec.reverse_speed:g} m/s")
        print(f"  PASS  input bound: {law} asks at most [{peaks}] (proved)")
    if design.output_warning is not None:
        print(f"  warning: {design.output_warning}")
    if args.plot:
        print(f"plot written to {args.plot}")
    if args.export is not None:
        print(f"tube written to {args.export}")
    return 0


def _sensing_line(sensing) -> str:
    """What ``[sensing]`` makes of the design at run time, in one line (state units:
    metres, as docs/sensing.md reads them)."""
    s = sensing
    axes = ", ".join(f"x{d + 1}" for d in s.dims)
    span = s.latency + s.replan_time + s.horizon
    return (f"  sensing: this tube is the first plan, replanned every {s.period:g} s; each "
            f"plan switches in {s.switch_delay:g} s after its measurement (latency "
            f"{s.latency:g} s + budget {s.replan_time:g} s), certified {s.horizon:g} s on "
            f"({s.shortest_horizon:g} s at least); obstacles of radius <= "
            f"{s.max_obstacle_radius:g} m at <= {s.max_obstacle_speed:g} m/s, seen within "
            f"{s.range:g} m on {axes}, close {s.unseen_reach(span):.3g} m within a plan's "
            f"{span:g} s (docs/sensing.md; simulate --sensed FILE)")


def configure_design(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen design``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``SPEC``, ``--json``, ``--quiet``, ``--export``,
        ``--plot``, ``--dims`` and the ``handler`` :func:`cmd_design`.
    """
    add_spec_argument(p)
    add_json_argument(p)
    add_quiet_argument(p)
    p.add_argument("--export", metavar="PATH", default=None,
                   help="write the tube at the controller's rate: t, gamma_L_i, gamma_U_i "
                        "per axis (.csv with a header row with units, or .npz)")
    add_plot_argument(p, "the designed tube (of the best rejected tube when there "
                      "is no design)")
    p.set_defaults(handler=cmd_design)
