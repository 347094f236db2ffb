"""``stt-codegen bench overhead``: what a command costs beyond the library call it makes.

For each command (``design``, ``generate``, ``verify`` of one spec) three CPU times (user +
system, from ``resource.getrusage``), best of ``runs``, the three measured in turn in each
run so that they share the machine's load:

* **command**: the process ``stt-codegen COMMAND SPEC ...`` (the console script next to
  this interpreter, else ``python -m stt_codegen.cli``);
* **script**: the process ``python -c`` of the same library calls through the front door
  (``import stt_codegen as s; s.design_tube(s.load_spec(SPEC))``...);
* **call**: within that script, the library call itself (``design_tube``, ``generate`` or
  ``verify`` after ``load_spec``, its modules imported first), from the process's own
  ``getrusage``.

``command - call`` is what the project bounds by 0.5 s (the interpreter, the imports, the
spec's schema, the command's own work); ``command - script`` is the command line's own
share. Wall times are not reported: the machine is shared. Whether the package's byte
code is cached matters (``PYTHONDONTWRITEBYTECODE`` compiles every module in every
process); the report says which.
"""

from __future__ import annotations

import importlib.util
import os
import resource
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

__all__ = ["COMMANDS", "format_overhead_report", "run_overhead_bench"]

#: Command -> (its arguments after the spec, the script's library call). ``{out}`` is a
#: temporary folder; the call runs after ``s = stt_codegen`` and ``spec = s.load_spec(...)``,
#: with the front door's names it uses imported first.
COMMANDS: dict[str, tuple[tuple[str, ...], str]] = {
    "design": ((), "s.design_tube(spec)"),
    "generate": (("-o", "{out}"), "s.generate(s.design_tube(spec), {out!r})"),
    "verify": ((), "s.verify(s.design_tube(spec))"),
}

#: The script: the front door's calls, and the CPU of the call alone on its last line.
_SCRIPT = """\
import resource, sys
import stt_codegen as s
{names}                                   # the call's modules imported first
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
spec = s.load_spec({spec!r})
begin = cpu()
{call}
print(cpu() - begin)
"""


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _timed(argv: list[str]) -> tuple[float, str]:
    """Run ``argv``; its CPU seconds (children included) and standard output."""
    before = _children_cpu()
    proc = subprocess.run(argv, capture_output=True, text=True)
    cpu = _children_cpu() - before
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} exited {proc.returncode}: {proc.stderr[-500:]}")
    return cpu, proc.stdout


def _command_line() -> list[str]:
    """The ``stt-codegen`` console script of this interpreter's environment."""
    script = Path(sys.executable).with_name("stt-codegen")
    if script.exists():
        return [str(script)]
    found = shutil.which("stt-codegen")
    return [found] if found else [sys.executable, "-m", "stt_codegen.cli"]


def _bytecode_cached() -> bool:
    """Whether the package's modules have cached byte code (``__pycache__``)."""
    spec = importlib.util.find_spec("stt_codegen.spec.loader")
    return bool(spec and spec.cached and os.path.exists(spec.cached))


def run_overhead_bench(spec: str = "omnirobot-s1", commands: tuple[str, ...] = ("design",),
                       runs: int = 5) -> dict:
    """Measure the commands and their library calls side by side.

    Parameters
    ----------
    spec : str
        A bundled case or a spec file.
    commands : tuple of str
        Keys of :data:`COMMANDS`.
    runs : int
        Runs of each measurement (the least CPU is reported), >= 1.

    Returns
    -------
    dict
        ``rows``: one per command with ``command``, ``command_s``, ``script_s``,
        ``call_s`` (least CPU seconds over the runs), ``over_call_s`` (command - call)
        and ``over_script_s`` (command - script); ``load`` (the 1-minute load average
        before and after), ``cpus``, ``bytecode_cached``, ``runs``, ``spec``.

    Raises
    ------
    ValueError
        An unknown command or ``runs`` below 1.
    RuntimeError
        A process failed.
    """
    unknown = [c for c in commands if c not in COMMANDS]
    if unknown or not commands:
        raise ValueError(f"unknown commands {unknown} (commands: {', '.join(COMMANDS)})")
    if runs < 1:
        raise ValueError(f"runs must be at least 1, got {runs}")
    load_before = os.getloadavg()[0]
    rows = []
    for name in commands:
        extra, call = COMMANDS[name]
        best = {"command": float("inf"), "script": float("inf"), "call": float("inf")}
        for _ in range(runs):
            with tempfile.TemporaryDirectory(prefix="stt-overhead-") as out:
                argv = [*_command_line(), name, spec, *(a.format(out=out) for a in extra)]
                best["command"] = min(best["command"], _timed(argv)[0])
            with tempfile.TemporaryDirectory(prefix="stt-overhead-") as out:
                names = ", ".join(f"s.{word}" for word in ("design_tube", "generate", "verify")
                                  if f"s.{word}(" in call)
                code = _SCRIPT.format(spec=spec, call=call.format(out=out), names=names)
                cpu, stdout = _timed([sys.executable, "-c", code])
                best["script"] = min(best["script"], cpu)
                best["call"] = min(best["call"], float(stdout.strip().splitlines()[-1]))
        rows.append({"command": name, "command_s": best["command"],
                     "script_s": best["script"], "call_s": best["call"],
                     "over_call_s": best["command"] - best["call"],
                     "over_script_s": best["command"] - best["script"]})
    return {"spec": spec, "runs": runs, "rows": rows, "cpus": len(os.sched_getaffinity(0)),
            "load": [load_before, os.getloadavg()[0]], "bytecode_cached": _bytecode_cached()}


def format_overhead_report(report: dict) -> str:
    """The report of :func:`run_overhead_bench` as a table (seconds of CPU, best of runs).

    Parameters
    ----------
    report : dict
        From :func:`run_overhead_bench`.

    Returns
    -------
    str
        One line per command, then the conditions.
    """
    lines = [f"CPU seconds (user + system), least of {report['runs']} runs, spec "
             f"{report['spec']}",
             f"{'command':<10} {'command':>8} {'script':>8} {'call':>8} "
             f"{'cmd-call':>9} {'cmd-script':>10}"]
    for row in report["rows"]:
        lines.append(f"{row['command']:<10} {row['command_s']:8.3f} {row['script_s']:8.3f} "
                     f"{row['call_s']:8.3f} {row['over_call_s']:9.3f} "
                     f"{row['over_script_s']:10.3f}")
    lines.append(f"load average {report['load'][0]:.2f} -> {report['load'][1]:.2f} on "
                 f"{report['cpus']} CPUs; byte code cached: "
                 f"{'yes' if report['bytecode_cached'] else 'no (every process compiles)'}")
    return "\n".join(lines)
