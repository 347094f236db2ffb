"""The ``stt-codegen`` command line: a thin layer over the library.

Exit codes (:data:`EXIT_CODES`, the one place that maps error kinds to codes):

* 0 success (``simulate``: the task is satisfied);
* 1 a negative outcome: ``simulate``: not satisfied; ``check``: drift; ``verify``: a check
  failed; any command: no tube can be designed for the spec (:class:`DesignError`);
* 2 bad input (:class:`SpecError`, or an argument argparse rejects);
* 3 a tool is missing or failed, or an internal failure (:class:`ToolchainError`);
* 130 interrupted.

Errors are one line ``error: ...`` on standard error, no traceback.

Subcommands are listed in :data:`COMMANDS` with their one-line help and the function that
configures their arguments; only the chosen command's module is imported, so ``--help``
and ``cases`` import nothing heavy.
"""

from __future__ import annotations

import argparse
import functools
import importlib
import json
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from .errors import DesignError, SpecError, SttError, ToolchainError
from .system import atomic_write

#: Every subcommand: name -> (one-line help, ``"module:function"``). The function takes the
#: subcommand's :class:`argparse.ArgumentParser`, adds its arguments and sets
#: ``handler=fn(args) -> int`` (the exit code). It is imported only when the command runs.
COMMANDS: dict[str, tuple[str, str]] = {
    "cases": ("list the bundled specs", "stt_codegen.cli:configure_cases"),
    "simulate": ("design the tube and simulate the closed loop",
                 "stt_codegen.cli:configure_simulate"),
    "demo": ("generate, compile and run the controller of every bundled case in closed "
             "loop; print a table, write code and plots", "stt_codegen.cli:configure_demo"),
    "generate": ("write the C and Python controllers of a spec",
                 "stt_codegen.codegen.cli:configure_generate"),
    "check": ("regenerate generated/ and compare (exit 1 on drift)",
              "stt_codegen.codegen.cli:configure_check"),
    "verify": ("check the paper's lemmas and certify the tube",
               "stt_codegen.verify.command:configure_verify"),
    "embedded": ("run the single-precision controller on an emulated Cortex-M4F",
                 "stt_codegen.embedded.cli:configure_embedded"),
    "bench": ("benchmarks: random arenas vs planners, step cost, scaling",
              "stt_codegen.bench.cli:configure_bench"),
    "design": ("design and certify the tube (no simulation)",
               "stt_codegen.design.cli:configure_design"),
    "schema": ("print the JSON Schema of spec files (for editors and tools)",
               "stt_codegen.cli:configure_schema"),
}

#: Error kind -> exit code; the first matching row wins.
EXIT_CODES: tuple[tuple[type[BaseException], int], ...] = (
    (SpecError, 2),
    (DesignError, 1),
    (ToolchainError, 3),
    (SttError, 3),
)


def _design(spec_arg: str):
    from .design.search import design_tube
    from .spec.loader import load_spec
    spec = load_spec(spec_arg)
    return spec, design_tube(spec)


def _plot_dims(text: str | None, spec) -> tuple[int, int]:
    """The arena's dimensions of ``--dims I,J`` for ``spec`` (SpecError ``dims`` if bad)."""
    from .runtime.plots import parse_dims
    return parse_dims(text, spec.dimension)


def _cmd_cases(args: argparse.Namespace) -> int:
    from .cases import bundled_cases
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
    from .design.search import design_tube
    from .runtime.simulate import simulate
    from .spec.loader import load_spec
    _check_output_folder(args.plot)
    spec = load_spec(args.spec)
    if args.plot or args.dims is not None:
        dims = _plot_dims(args.dims, spec)
    designed = design_tube(spec)
    design = designed.tube
    result = simulate(spec, design, backend=args.backend, horizon=args.horizon, seed=args.seed)
    if args.plot:
        from .runtime.plots import plot_run
        atomic_write(Path(args.plot), lambda tmp: plot_run(spec, design, result, tmp,
                                                           dims=dims))
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
    from .cases import bundled_cases
    from .spec.loader import load_spec
    dims = {name: _plot_dims(args.dims, load_spec(name)) for name in bundled_cases()}
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
        atomic_write(out / f"{name}.png",
                     lambda tmp: plot_run(spec, design, result, tmp, dims=dims[name]))
        print(_summary_line(result), flush=True)
        all_ok &= result.satisfied
    print(f"generated code in {out}/<case>/, plots in {out}/<case>.png")
    return 0 if all_ok else 1


def configure_cases(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen cases`` (none)."""
    p.set_defaults(handler=_cmd_cases)


def _cmd_schema(args: argparse.Namespace) -> int:
    from .spec.schema import json_schema
    print(json.dumps(json_schema(), indent=2, sort_keys=True))
    return 0


def configure_schema(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen schema`` (none)."""
    p.set_defaults(handler=_cmd_schema)


def _backend_argument(p: argparse.ArgumentParser) -> None:
    from .runtime.backends import backend_names
    p.add_argument("--backend", default=default_backend(), choices=backend_names(),
                   help="controller implementation (default: %(default)s)")


def _dims_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--dims", metavar="I,J", help="state dimensions of the plot's arena, "
                   "zero-based (default: 0,1)")


def configure_simulate(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen simulate``."""
    p.add_argument("spec", metavar="SPEC", help="bundled case name or spec file")
    _backend_argument(p)
    p.add_argument("--horizon", type=float, default=None, metavar="S",
                   help="simulated time in seconds (default: t_c)")
    p.add_argument("--seed", type=int, default=0, help="disturbance seed (default: 0)")
    p.add_argument("--plot", metavar="PNG", help="write a figure of the run")
    _dims_argument(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_cmd_simulate)


def configure_demo(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen demo``."""
    p.add_argument("--out", default="stt-demo", metavar="DIR",
                   help="folder for the generated code and the plots (default: %(default)s)")
    _backend_argument(p)
    _dims_argument(p)
    p.set_defaults(handler=_cmd_demo)


def default_backend() -> str:
    """The backend ``simulate`` and ``demo`` use unless told otherwise."""
    return "c"


class _CommandParser(argparse.ArgumentParser):
    """An argument parser that remembers the option of each destination, ``flags[dest]``.

    The dictionary is shared with the parsers of nested subcommands (``bench arenas``), so
    an error about a library parameter (``SpecError("horizon", ...)``) can be reported
    with the flag the user typed (``--horizon``).
    """

    def __init__(self, *args, flags: dict[str, str] | None = None, **kwargs) -> None:
        self.flags: dict[str, str] = {} if flags is None else flags
        super().__init__(*args, **kwargs)

    def add_argument(self, *args, **kwargs):
        action = super().add_argument(*args, **kwargs)
        if action.option_strings:
            self.flags.setdefault(action.dest, max(action.option_strings, key=len))
        return action

    def add_subparsers(self, **kwargs):
        kwargs.setdefault("parser_class", functools.partial(_CommandParser, flags=self.flags))
        return super().add_subparsers(**kwargs)


def _chosen_command(argv: Sequence[str]) -> str | None:
    """The subcommand named in ``argv``: the first argument that is not an option."""
    return next((a for a in argv if not a.startswith("-")), None)


def _configure(parser: argparse.ArgumentParser, command: str) -> None:
    module_name, function_name = COMMANDS[command][1].split(":")
    getattr(importlib.import_module(module_name), function_name)(parser)


def build_parser(argv: Sequence[str] = ()) -> argparse.ArgumentParser:
    """The argument parser: every subcommand's name and help, and the arguments of the
    subcommand named in ``argv`` (only its module is imported)."""
    from . import __version__
    parser = argparse.ArgumentParser(
        prog="stt-codegen",
        description="Spatiotemporal-tube controllers for prescribed-time reach-avoid-stay "
                    "tasks. Exit codes: 0 success, 1 negative outcome (not satisfied, no "
                    "design, a check failed, drift), 2 bad input, 3 tool or internal "
                    "failure.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                parser_class=_CommandParser)
    chosen = _chosen_command(argv)
    for name, (help_text, _) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text)
        if name == chosen:
            _configure(p, name)
            parser.set_defaults(command_parser=p)
    return parser


def exit_code(exc: BaseException) -> int:
    """The exit code of an error kind (:data:`EXIT_CODES`)."""
    return next(code for kind, code in EXIT_CODES if isinstance(exc, kind))


def _message(exc: SttError, flags: dict[str, str]) -> str:
    """``exc``'s one-line message; a library parameter is named by its command-line flag."""
    if isinstance(exc, SpecError) and exc.field in flags:
        return f"{flags[exc.field]}: {exc.reason}"
    return str(exc)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``stt-codegen`` console script; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args))
    except SttError as exc:
        print(f"error: {_message(exc, args.command_parser.flags)}", file=sys.stderr)
        return exit_code(exc)
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader went away (``stt-codegen design ... | head``): stop quietly, as a Unix
        # filter does; point stdout at devnull so the interpreter's final flush is silent
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141


if __name__ == "__main__":
    sys.exit(main())
