"""The ``stt-codegen`` command line.

Exit codes: 0 success (``simulate``: the task is satisfied), 1 a negative outcome
(``simulate``: not satisfied; ``check``: drift; ``verify``: a check failed; any command:
no tube can be designed for the spec), 2 bad input (one line ``error: ...`` on standard
error, no traceback).
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

from .errors import DesignError, SpecError, SttError

#: Modules that add subcommands through ``register_cli(subparsers)``.
COMMAND_MODULES = ("stt_codegen.design", "stt_codegen.codegen", "stt_codegen.verify",
                   "stt_codegen.embedded", "stt_codegen.bench")


def atomic_write_bytes(path: Path, writer) -> None:
    """Call ``writer(tmp_path)`` then move the file into place: never half-written."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise SpecError("output", f"folder {str(folder)!r} does not exist")
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=path.suffix)
    os.close(fd)
    try:
        writer(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _design(spec_arg: str):
    from .design.search import design_tube
    from .spec.loader import load_spec
    spec = load_spec(spec_arg)
    return spec, design_tube(spec)


def _cmd_cases(args: argparse.Namespace) -> int:
    from .spec.loader import bundled_cases
    for name in bundled_cases():
        print(name)
    return 0


def _summary_line(result) -> str:
    clearance = ("-" if result.min_obstacle_clearance is None
                 else f"{result.min_obstacle_clearance:.3f}")
    reach = "-" if result.reach_time is None else f"{result.reach_time:.3f}"
    u_max = ", ".join(f"{v:.3g}" for v in result.max_abs_u)
    return (f"{result.spec:<22} {'yes' if result.satisfied else 'NO':<9} {reach:>9} "
            f"{clearance:>9}   [{u_max}]")


SUMMARY_HEADER = f"{'case':<22} {'satisfied':<9} {'reach [s]':>9} {'clearance':>9}   max |u|"


def _check_output_folder(path: str | None) -> None:
    if path:
        folder = Path(path).parent
        if not folder.is_dir():
            raise SpecError("--plot", f"folder {str(folder)!r} does not exist")


def _cmd_simulate(args: argparse.Namespace) -> int:
    from .runtime.simulate import simulate
    _check_output_folder(args.plot)
    spec, designed = _design(args.spec)
    design = designed.tube
    result = simulate(spec, design, backend=args.backend, horizon=args.horizon, seed=args.seed)
    if args.plot:
        from .runtime.plots import plot_run
        atomic_write_bytes(Path(args.plot), lambda tmp: plot_run(spec, design, result, tmp))
    if args.json:
        data = result.to_json()
        data["design"] = designed.to_json(spec.name)
        print(json.dumps(data, indent=2, sort_keys=True))
    else:
        print(SUMMARY_HEADER)
        print(_summary_line(result))
        print(f"backend {result.backend}, {result.steps} steps at {design.rate_hz:g} Hz, "
              f"t_c = {result.prescribed_time:g} s, gain k = {design.gain:.4g}, "
              f"stayed in tube: {'yes' if result.stayed_in_tube else 'NO'}, "
              f"collision: {'YES' if result.collision else 'no'}, "
              f"left state space: {'YES' if result.left_state_space else 'no'}")
        if args.plot:
            print(f"plot written to {args.plot}")
    return 0 if result.satisfied else 1


def _cmd_demo(args: argparse.Namespace) -> int:
    from .codegen import Options, generate_files, write_generation
    from .runtime.plots import plot_run
    from .runtime.simulate import simulate
    from .spec.loader import bundled_cases
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"For every bundled case: design the tube, generate the C and Python controllers "
          f"into {out}/<case>/, and run the {args.backend} controller in closed loop.")
    print(SUMMARY_HEADER)
    all_ok = True
    for name in bundled_cases():
        spec, designed = _design(name)
        design = designed.tube
        write_generation(out / name, generate_files(spec, design, Options()))
        result = simulate(spec, design, backend=args.backend)
        atomic_write_bytes(out / f"{name}.png", lambda tmp: plot_run(spec, design, result, tmp))
        print(_summary_line(result), flush=True)
        all_ok &= result.satisfied
    print(f"generated code in {out}/<case>/, plots in {out}/<case>.png")
    return 0 if all_ok else 1


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    from .runtime.backends import backend_names
    parser = argparse.ArgumentParser(
        prog="stt-codegen",
        description="Spatiotemporal-tube controllers for prescribed-time reach-avoid-stay tasks.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("cases", help="list the bundled specs")
    p.set_defaults(handler=_cmd_cases)

    p = sub.add_parser("simulate", help="design the tube and simulate the closed loop")
    p.add_argument("spec", metavar="SPEC", help="bundled case name or spec file")
    p.add_argument("--backend", default=default_backend(), choices=backend_names(),
                   help="controller implementation (default: %(default)s)")
    p.add_argument("--horizon", type=float, default=None, metavar="S",
                   help="simulated time in seconds (default: t_c)")
    p.add_argument("--seed", type=int, default=0, help="disturbance seed (default: 0)")
    p.add_argument("--plot", metavar="PNG", help="write a figure of the run")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_cmd_simulate)

    p = sub.add_parser("demo", help="generate, compile and run the controller of every bundled "
                                    "case in closed loop; print a table, write code and plots")
    p.add_argument("--out", default="stt-demo", metavar="DIR",
                   help="folder for the generated code and the plots (default: %(default)s)")
    p.add_argument("--backend", default=default_backend(), choices=backend_names(),
                   help="controller implementation (default: %(default)s)")
    p.set_defaults(handler=_cmd_demo)

    for module_name in COMMAND_MODULES:
        importlib.import_module(module_name).register_cli(sub)
    return parser


def default_backend() -> str:
    """The backend ``simulate`` and ``demo`` use unless told otherwise."""
    return "c"


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``stt-codegen`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args))
    except DesignError as exc:  # a valid spec the method cannot serve: a negative outcome
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except SttError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
