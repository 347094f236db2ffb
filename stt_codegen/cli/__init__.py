"""The ``stt-codegen`` command line: a thin layer over the library, at the bottom of the
package's layers (no library module imports it).

Exit codes (:data:`EXIT_CODES`, the one place that maps error kinds to codes):

* 0 success (``simulate``: the task is satisfied);
* 1 a negative outcome: ``simulate``: not satisfied; ``check``: drift; ``verify``: a check
  failed; any command that designs: no tube can be designed for the spec
  (:class:`DesignError`);
* 2 bad input (:class:`SpecError`, or an argument argparse rejects);
* 3 a tool is missing or failed, or an internal failure (:class:`ToolchainError`);
* 130 interrupted.

Errors are one line ``error: ...`` on standard error, no traceback.

Subcommands are listed in :data:`COMMANDS` with their one-line help and the function that
configures their arguments, one small module a command (:mod:`.design`, :mod:`.simulate`,
:mod:`.demo`, :mod:`.generate`, :mod:`.check`, :mod:`.verify`, :mod:`.embedded`,
:mod:`.cases`, :mod:`.schema`); another distribution adds one through the entry-point group
:data:`COMMAND_GROUP` (``bench``, :data:`OPTIONAL_COMMANDS`); what several share is in
:mod:`.common` (arguments, the design step and its no-design document) and :mod:`.plotting`
(``--plot``).
Only the chosen command's module is imported, so ``--help`` and ``cases`` import nothing
heavy.
"""

from __future__ import annotations

import argparse
import functools
import importlib
import os
import sys
import warnings
from collections.abc import Sequence

from ..errors import DesignError, SpecError, SttError, ToolchainError
from ..version import __version__
from .parser import CommandParser

__all__ = ["COMMANDS", "COMMAND_GROUP", "EXIT_CODES", "OPTIONAL_COMMANDS", "build_parser", "exit_code", "main"]

#: Every subcommand: name -> (one-line help, ``"module:function"``). The function takes the
#: subcommand's :class:`argparse.ArgumentParser`, adds its arguments and sets
#: ``handler=fn(args) -> int`` (the exit code). It is imported only when the command runs.
COMMANDS: dict[str, tuple[str, str]] = {
    "cases": ("list the bundled specs", "stt_codegen.cli.cases:configure_cases"),
    "simulate": ("design the tube and simulate the closed loop",
                 "stt_codegen.cli.simulate:configure_simulate"),
    "demo": ("generate, compile and run the controller of every bundled case in closed "
             "loop; print a table, write code and plots",
             "stt_codegen.cli.demo:configure_demo"),
    "generate": ("write the C and Python controllers of a spec",
                 "stt_codegen.cli.generate:configure_generate"),
    "check": ("regenerate generated/ and compare (exit 1 on drift)",
              "stt_codegen.cli.check:configure_check"),
    "verify": ("check the paper's lemmas and certify the tube",
               "stt_codegen.cli.verify:configure_verify"),
    "embedded": ("run the single-precision controller on an emulated Cortex-M4F",
                 "stt_codegen.cli.embedded:configure_embedded"),
    "design": ("design and certify the tube (no simulation)",
               "stt_codegen.cli.design:configure_design"),
    "schema": ("print the JSON Schema of spec files (for editors and tools)",
               "stt_codegen.cli.schema:configure_schema"),
    "import": ("write a spec from another tool's task (gymnasium-robotics' PointMaze)",
               "stt_codegen.cli.import_spec:configure_import"),
}

#: The entry-point group through which another distribution adds a subcommand: the entry
#: point's name is the command, its value the ``"module:function"`` configuring it, as in
#: :data:`COMMANDS` (the benchmarks' ``tests/benchmarks/pyproject.toml`` adds ``bench``).
COMMAND_GROUP = "stt_codegen.commands"

#: The subcommands of other distributions, listed by ``--help`` whether installed or not:
#: name -> (one-line help, the command that installs it). Not installed, the command says
#: how to install it and exits 3 (a missing tool).
OPTIONAL_COMMANDS: dict[str, tuple[str, str]] = {
    "bench": ("benchmarks: random arenas vs planners, step cost, scaling (installed apart)",
              "python3 -m pip install ./tests/benchmarks"),
}

#: Error kind -> exit code; the first matching row wins.
EXIT_CODES: tuple[tuple[type[BaseException], int], ...] = (
    (SpecError, 2),
    (DesignError, 1),
    (ToolchainError, 3),
    (SttError, 3),
)


def _chosen_command(argv: Sequence[str]) -> str | None:
    """The subcommand named in ``argv``: the first argument that is not an option."""
    return next((a for a in argv if not a.startswith("-")), None)


def _configure(parser: argparse.ArgumentParser, command: str) -> None:
    if command in COMMANDS:
        target = COMMANDS[command][1]
    else:
        from importlib.metadata import entry_points
        found = entry_points(group=COMMAND_GROUP, name=command)
        if not found:
            parser.add_argument("rest", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
            parser.set_defaults(handler=functools.partial(_not_installed, command))
            return
        target = next(iter(found)).value
    module_name, function_name = target.split(":")
    getattr(importlib.import_module(module_name), function_name)(parser)


def _not_installed(command: str, args: argparse.Namespace) -> int:
    """The handler of an optional command whose distribution is not installed."""
    raise ToolchainError(f"stt-codegen {command} is not installed; install it with "
                         f"{OPTIONAL_COMMANDS[command][1]}")


def build_parser(argv: Sequence[str] = ()) -> argparse.ArgumentParser:
    """The argument parser: every subcommand's name and help, and the arguments of the
    subcommand named in ``argv`` (only its module is imported).

    Parameters
    ----------
    argv : sequence of str, optional
        The command line (without the program name); only the subcommand it names gets its
        arguments configured. Empty: every subcommand listed, none configured.

    Returns
    -------
    argparse.ArgumentParser
        The ``stt-codegen`` parser; for the chosen subcommand its defaults hold ``handler``
        (``fn(args) -> int``) and ``command_parser`` (its :class:`CommandParser`).
    """
    parser = argparse.ArgumentParser(
        prog="stt-codegen",
        description="Spatiotemporal-tube controllers for prescribed-time reach-avoid-stay "
                    "tasks. Exit codes: 0 success, 1 negative outcome (not satisfied, no "
                    "design, a check failed, drift), 2 bad input, 3 tool or internal "
                    "failure.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                parser_class=CommandParser)
    chosen = _chosen_command(argv)
    listed = {name: help_text for name, (help_text, _) in (COMMANDS | OPTIONAL_COMMANDS).items()}
    for name, help_text in listed.items():
        p = sub.add_parser(name, help=help_text)
        if name == chosen:
            _configure(p, name)
            parser.set_defaults(command_parser=p)
    return parser


def exit_code(exc: BaseException) -> int:
    """The exit code of an error kind (:data:`EXIT_CODES`).

    Parameters
    ----------
    exc : BaseException
        The error a command raised.

    Returns
    -------
    int
        The code of the first row of :data:`EXIT_CODES` whose kind ``exc`` is an instance of.

    Raises
    ------
    StopIteration
        ``exc`` is none of the kinds of :data:`EXIT_CODES` (not an :class:`SttError`).
    """
    return next(code for kind, code in EXIT_CODES if isinstance(exc, kind))


def _message(exc: SttError, flags: dict[str, str]) -> str:
    """``exc``'s one-line message; a library parameter is named by its command-line flag."""
    if isinstance(exc, SpecError) and exc.field in flags:
        return f"{flags[exc.field]}: {exc.reason}"
    return str(exc)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``stt-codegen`` console script; returns the exit code.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments without the program name; ``None`` reads ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit code: the handler's (0 success, 1 a negative outcome), or the code of the
        :class:`SttError` it raised (:func:`exit_code`; the message on standard error), 130 on
        an interrupt, 141 when standard output was closed by its reader. argparse exits with 2
        on arguments it rejects.
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning
        return _run(args)


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as one line on standard error (``warning: FIELD: REASON``), no source."""
    print(f"warning: {message}", file=sys.stderr if file is None else file)


def _run(args) -> int:
    """The chosen command's handler, its errors turned into exit codes (:func:`main`)."""
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
