"""``stt-codegen embedded SPEC``: the single-precision controller on an emulated Cortex-M4F."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..embedded.budget import budget_words
from ..errors import SpecError
from .common import (add_json_argument, add_seed_argument, add_spec_argument,
                     add_tube_data_argument, checked_seed, load_and_design, print_json)

__all__ = ["cmd_embedded", "configure_embedded", "law13_command", "tube_data_command",
           "variant_loop_command"]


def _judged(r: dict) -> str:
    """The tasks and moving obstacles judged on the printed states, in words ("" without)."""
    words = ""
    if "tasks" in r:
        words += f", tasks met {sum(t['met'] for t in r['tasks'])}/{len(r['tasks'])}"
    if "moving_clearance" in r:
        clear = r["moving_clearance"]
        words += ", moving obstacles " + ("never active" if clear is None else
                                          f"clearance {clear:.3f}")
    return words


def _print_report(r: dict) -> None:
    print(f"{r['spec']} on {r['target']}")
    print(f"  self-test: {r['vectors_passed']} passed, {r['vectors_failed']} failed; "
          f"max rel. error of u {r['max_rel_error_u']:.3g}; error/bound: "
          + ", ".join(f"{k} {v:.3g}" for k, v in r["error_to_bound"].items()))
    print(f"  flash {r['flash_bytes']} B (linked {r['flash_bytes_linked']} B), "
          f"RAM {r['ram_bytes']} B, stack {r['stack_bytes']} B static "
          f"({r['stack_bytes_measured']} B measured)")
    print(f"  {r['instructions_per_step']} instructions per step "
          f"(counts {r['instructions_detail']['counts']}); {budget_words(r)}")
    top = list(r["instructions_detail"]["by_function"].items())[:6]
    if top:
        print("  most instructions in: " + ", ".join(
            f"{name} {v['instructions']:g} ({v['entries']:g} calls)" for name, v in top))
    clear = "-" if r["min_clearance"] is None else f"{r['min_clearance']:.3f}"
    reach = "-" if r["reach_time"] is None else f"{r['reach_time']:.3f}"
    print(f"  closed loop: {'satisfied' if r['closed_loop_satisfied'] else 'NOT satisfied'}"
          f", reach {reach} s, clearance {clear}{_judged(r)}, {r['steps']} steps, "
          f"outside-tube steps {r['outside_tube_steps']}")
    if "max_state_deviation" in r:
        print(f"  max |x_target - x_host| = {r['max_state_deviation']:.3g}")


def cmd_embedded(args: argparse.Namespace) -> int:
    """Design, generate single precision, run on QEMU mps2-an386; 0 iff all passed.

    Parameters
    ----------
    args : argparse.Namespace
        ``spec``, ``json``, ``seed``, ``build_dir`` (kept build folder or ``None``),
        ``no_host`` (skip the comparison with the host simulation) and ``tube_data``
        (``None``, or a capacity: the tube as data's switches and steps instead).

    Returns
    -------
    int
        0 every check of the run passed (the cascade: the task satisfied), 1 otherwise or no
        design.

    Raises
    ------
    SpecError
        A bad spec, ``--seed``, ``--tube-data`` or ``--build-dir`` whose folder does not
        exist (exit code 2).
    ToolchainError
        The Arm toolchain or QEMU is missing or fails (exit code 3).
    """
    seed = checked_seed(args)
    if args.build_dir is not None and not Path(args.build_dir).parent.is_dir():
        raise SpecError("build_dir", f"folder {str(Path(args.build_dir).parent)!r} does not exist")
    capacity = None
    if args.tube_data is not None:
        from ..codegen.tube_data import parse_capacity
        capacity = parse_capacity(args.tube_data)
    design = load_and_design(args)
    from ..spec.variants import variant_of
    if capacity is not None:
        return tube_data_command(design, args, capacity)
    return variant_of(design.spec).entry("embedded_command")(design, args, seed)


def tube_data_command(design, args: argparse.Namespace, capacity) -> int:
    """``stt-codegen embedded SPEC --tube-data``: the tube as data on the Cortex-M4F
    (:func:`~stt_codegen.embedded.tube_data_loop.run_tube_data`), summarised.

    Parameters
    ----------
    design : Design
        A first-order design.
    args : argparse.Namespace
        ``json``, ``build_dir``.
    capacity : TubeCapacity
        The data form's capacity.

    Returns
    -------
    int
        0 if the self-test passed and every switch and step was accepted, else 1.
    """
    from ..embedded.tube_data_loop import run_tube_data
    r = run_tube_data(design, capacity, args.build_dir)
    if args.json:
        print_json(r)
    else:
        def span(counts):
            return f"{round(sum(counts) / len(counts))} ({min(counts)}-{max(counts)})"
        cost = r["cost_tube"]
        print(f"{r['spec']}, the tube as data ({capacity.segments} segments, "
              f"{capacity.windows} windows), on {r['target']}")
        print(f"  self-test on the spec's tube: {r['vectors_passed']} passed, "
              f"{r['vectors_failed']} failed; flash {r['flash_bytes']} B, RAM "
              f"{r['ram_bytes']} B, P_run's stack {r['stack_bytes_run']} B static (P.o)")
        print(f"  the spec's tube: switch {r['switch_design']['instructions']} instructions, "
              f"step {span(r['steps_design']['instructions'])} instructions")
        print(f"  a tube of {cost['segments']} segments with {cost['open_windows']} windows "
              f"open: switch {r['switch_cost']['instructions']} instructions, step "
              f"{span(r['steps_cost']['instructions'])} instructions")
        wire = r["wire"]
        print(f"  that tube packed on the host ({wire['bytes']} B) and copied in: check "
              f"{wire['check']}, steps {'the same' if wire['same_steps'] else 'DIFFERENT'}"
              f" bit for bit")
    return 0 if r["ok"] else 1


def variant_loop_command(design, args: argparse.Namespace, seed: int) -> int:
    """``stt-codegen embedded`` for the cascade or the look-ahead law (their role
    ``embedded_command``, :mod:`~stt_codegen.spec.variants`): the variant's closed loop
    on the Cortex-M4F (role ``firmware``), summarised.

    Parameters
    ----------
    design : Design
        The spec's design.
    args : argparse.Namespace
        ``json``.
    seed : int
        The disturbance's seed.

    Returns
    -------
    int
        0 if the closed loop satisfied the spec, else 1.
    """
    from ..spec.variants import variant_of
    variant = variant_of(design.spec)
    report = variant.entry("firmware")(design, seed=seed)
    if args.json:
        print_json(report)
    else:
        print(f"{design.spec.name} ({variant.name}) on the Cortex-M4F (QEMU "
              "mps2-an386): "
              f"{'satisfied' if report['satisfied'] else 'NOT satisfied'}, reach "
              f"{report['reach_time']} s, clearance {report['min_clearance']:.3f}"
              f"{_judged(report)}; {budget_words(report)}")
    return 0 if report["satisfied"] else 1


def law13_command(design, args: argparse.Namespace, seed: int) -> int:
    """``stt-codegen embedded`` for law (13) (the first-order role ``embedded_command``):
    the self-test, the footprint and the closed loop, beside the host simulation unless
    ``--no-host``.

    Parameters
    ----------
    design : Design
        The spec's design.
    args : argparse.Namespace
        ``json``, ``build_dir``, ``no_host``.
    seed : int
        The disturbance's seed.

    Returns
    -------
    int
        0 if everything passed, else 1.
    """
    from ..embedded.deploy import run_embedded
    report = run_embedded(design, args.build_dir, seed=seed,
                          compare_host=not args.no_host)
    if args.json:
        print_json(report)
    else:
        _print_report(report)
    return 0 if report["ok"] else 1


def configure_embedded(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen embedded``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``SPEC``, ``--json``, ``--seed``, ``--build-dir``,
        ``--no-host``, ``--tube-data`` and the ``handler`` :func:`cmd_embedded`.
    """
    add_spec_argument(p)
    add_json_argument(p)
    add_seed_argument(p)
    p.add_argument("--build-dir", default=None, metavar="DIR",
                   help="keep the generated code, programs and ELFs there (default: temporary)")
    p.add_argument("--no-host", action="store_true",
                   help="skip the comparison with the host simulation")
    add_tube_data_argument(p)
    p.set_defaults(handler=cmd_embedded)
