"""Build a bare-metal Cortex-M4F program and run it under QEMU (``mps2-an386``).

The program is linked with the board files of :mod:`stt_codegen.embedded.board`
(vector table, FPU enable, linker script) and newlib with semihosting
(``--specs=rdimon.specs``): ``printf`` goes to QEMU's standard output and the
return value of ``main`` becomes QEMU's exit status (semihosting
``SYS_EXIT_EXTENDED``).

Instruction counts come from QEMU's execution trace: with ``-singlestep`` every
translation block is one guest instruction and ``-d exec,nochain`` logs every
executed block, so the log has one line per executed instruction. The host
counts the lines between the return from ``stt_measure_begin()`` and the entry
of ``stt_measure_end()``, minus the ``bl stt_measure_end`` itself, and splits them by
function with the ELF's symbol table (:func:`profile_regions`). The count is
exact for the emulated instruction stream (conditional instructions that are
skipped still count); it is not a cycle count (QEMU models no pipeline, caches,
wait states, and no DWT cycle counter: ``DWT->CYCCNT`` reads 0 on mps2-an386).
"""

from __future__ import annotations

import bisect
import re
import subprocess
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from stt_codegen.embedded import board
from stt_codegen.embedded.toolchain import ToolError, Toolchain, find_toolchain, run_tool
from stt_codegen.errors import ToolchainError

__all__ = ["BuildError", "BuildResult", "CPU_FLAGS", "RunError", "RunResult", "build_elf",
           "TARGET_WORDS", "count_region_instructions", "elf_sizes", "profile_regions",
           "run_checked", "run_qemu"]

#: Code generation flags for the Cortex-M4F (single-precision FPU, hard-float ABI).
CPU_FLAGS: tuple[str, ...] = (
    "-mcpu=cortex-m4", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard", "-mthumb",
)
#: Compile flags (besides CPU_FLAGS, -O level, includes and defines).
COMPILE_FLAGS: tuple[str, ...] = (
    "-std=c99", "-Wall", "-Wextra", "-ffunction-sections", "-fdata-sections",
    "-fno-common", "-fstack-usage", "-g",
)
#: Link flags (besides CPU_FLAGS and the linker script).
LINK_FLAGS: tuple[str, ...] = (
    "--specs=rdimon.specs", "-nostartfiles", "-Wl,--gc-sections",
)
LINK_LIBS: tuple[str, ...] = ("-lm",)
#: The target and its build, in a report's words.
TARGET_WORDS = "Cortex-M4F (QEMU mps2-an386), " + " ".join(CPU_FLAGS) + " -O2, newlib"

#: Flags the board's startup file is compiled with (gnu99: inline asm).
_STARTUP_FLAGS: tuple[str, ...] = ("-std=gnu99", "-Wall", "-ffunction-sections",
                                   "-fdata-sections", "-fno-common", "-g")


class BuildError(ToolError):
    """The cross compiler or linker failed (``command``, ``output``).

    Parameters
    ----------
    command : sequence of str
        The command that failed.
    output : str
        Its standard error and output.
    """


class RunError(ToolchainError):
    """QEMU could not run the program, or the trace could not be interpreted."""


@dataclass(frozen=True)
class BuildResult:
    """Outcome of :func:`build_elf`.

    Attributes
    ----------
    elf : Path
        Linked program.
    objects : tuple of Path
        Object files of the given sources (the board's startup object excluded),
        in the order of the sources.
    su_files : tuple of Path
        ``-fstack-usage`` files, one per object.
    map_file : Path
        Linker map.
    compile_command, link_command : tuple of str
        Exact commands used (first source / the link).
    elf_sizes : dict
        ``text``, ``data``, ``bss`` of the whole ELF (Berkeley ``size``),
        including startup and newlib.
    """

    elf: Path
    objects: tuple[Path, ...]
    su_files: tuple[Path, ...]
    map_file: Path
    compile_command: tuple[str, ...]
    link_command: tuple[str, ...]
    elf_sizes: dict[str, int] = field(default_factory=dict)


@dataclass(frozen=True)
class RunResult:
    """Outcome of :func:`run_qemu`.

    Attributes
    ----------
    stdout : str
        What the program wrote through semihosting (QEMU's standard output).
    exit_code : int or None
        The program's exit status (``main``'s return value or ``exit`` argument;
        ``board.FAULT_EXIT_STATUS`` after a fault); ``None`` on timeout.
    instructions : list of int or None
        Instructions executed in each measured region
        (``stt_measure_begin``/``stt_measure_end``), in order; ``None`` when not
        counted.
    timed_out : bool
        QEMU was killed after the timeout.
    stderr : str
        QEMU's standard error (semihosting ``SYS_WRITE0`` console output, e.g.
        the fault message of the startup code).
    command : tuple of str
        The QEMU command line.
    functions : list of dict or None
        When counted, per region ``{function: [instructions, entries]}``
        (:func:`profile_regions`): where the region's instructions were executed.
    """

    stdout: str
    exit_code: int | None
    instructions: list[int] | None
    timed_out: bool = False
    stderr: str = ""
    command: tuple[str, ...] = ()
    functions: list[dict[str, list[int]]] | None = None


def _build(cmd: Sequence[str]) -> None:
    try:
        run_tool(cmd)
    except ToolError as err:
        raise BuildError(err.command, err.output) from None


def write_board_files(directory: Path) -> dict[str, Path]:
    """Write the board's startup, header and linker script into ``directory``.

    Parameters
    ----------
    directory : Path
        Destination (created if needed).

    Returns
    -------
    dict
        ``{"startup": ..., "header": ..., "linker_script": ...}`` paths.
    """
    directory.mkdir(parents=True, exist_ok=True)
    files = {
        "startup": (board.STARTUP_NAME, board.STARTUP),
        "header": (board.HEADER_NAME, board.HEADER),
        "linker_script": (board.LINKER_SCRIPT_NAME, board.LINKER_SCRIPT),
    }
    out: dict[str, Path] = {}
    for key, (name, text) in files.items():
        path = directory / name
        if not path.exists() or path.read_text() != text:
            path.write_text(text)
        out[key] = path
    return out


def _define_flags(defines: Mapping[str, str | int | float | None] | None) -> list[str]:
    flags = []
    for name, value in (defines or {}).items():
        flags.append(f"-D{name}" if value is None else f"-D{name}={value}")
    return flags


def elf_sizes(elf: Path, toolchain: Toolchain | None = None) -> dict[str, int]:
    """Berkeley ``text``/``data``/``bss`` of a linked ELF.

    Parameters
    ----------
    elf : Path
        Linked program.
    toolchain : Toolchain, optional
        Tools to use (found on ``PATH`` by default).

    Returns
    -------
    dict
        Keys ``text``, ``data``, ``bss``.
    """
    tc = toolchain or find_toolchain(need_qemu=False)
    lines = run_tool([str(tc.size), "-B", str(elf)]).splitlines()
    text, data, bss = (int(v) for v in lines[1].split()[:3])
    return {"text": text, "data": data, "bss": bss}


def build_elf(sources: Sequence[Path], include_dirs: Iterable[Path] = (),
              out_dir: Path | None = None,
              defines: Mapping[str, str | int | float | None] | None = None, *,
              opt: str = "-O2", extra_cflags: Sequence[str] = (),
              name: str = "prog") -> BuildResult:
    """Compile and link C sources into a Cortex-M4F ELF for QEMU ``mps2-an386``.

    Each source is compiled separately (so that its object and ``.su`` file can
    be measured), the board startup is added, and everything is linked against
    newlib with semihosting.

    Parameters
    ----------
    sources : sequence of Path
        C files; one must define ``int main(void)``.
    include_dirs : iterable of Path, optional
        Extra ``-I`` directories (the board header ``stt_target.h`` is always
        on the include path).
    out_dir : Path, optional
        Build directory (objects, ``.su``, map, ELF, board files). A new
        temporary directory by default.
    defines : mapping, optional
        Preprocessor macros, ``{"N": 3, "FLAG": None}``.
    opt : str, optional
        Optimisation flag (default ``"-O2"``).
    extra_cflags : sequence of str, optional
        Further compile flags for the given sources.
    name : str, optional
        Stem of the ELF and map file names.

    Returns
    -------
    BuildResult
        Paths and commands.

    Raises
    ------
    MissingTool
        If the cross toolchain or newlib is not installed.
    BuildError
        If compiling or linking fails.
    """
    tc = find_toolchain(need_qemu=False)
    out = Path(out_dir) if out_dir is not None else Path(tempfile.mkdtemp(prefix="stt-embedded-"))
    out.mkdir(parents=True, exist_ok=True)
    board_dir = out / "board"
    bfiles = write_board_files(board_dir)
    obj_dir = out / "obj"
    obj_dir.mkdir(exist_ok=True)

    incs = [f"-I{d}" for d in include_dirs] + [f"-I{board_dir}"]
    dflags = _define_flags(defines)
    objects: list[Path] = []
    su_files: list[Path] = []
    first_cmd: list[str] = []
    for i, src in enumerate(sources):
        src = Path(src)
        obj = obj_dir / f"{i:02d}_{src.stem}.o"
        cmd = [str(tc.gcc), *CPU_FLAGS, opt, *COMPILE_FLAGS, *extra_cflags, *dflags,
               *incs, "-c", str(src), "-o", str(obj)]
        _build(cmd)
        first_cmd = first_cmd or cmd
        objects.append(obj)
        su_files.append(obj.with_suffix(".su"))

    startup_obj = obj_dir / "board_startup.o"
    _build([str(tc.gcc), *CPU_FLAGS, "-O2", *_STARTUP_FLAGS,
          "-fno-tree-loop-distribute-patterns", f"-I{board_dir}", "-c",
          str(bfiles["startup"]), "-o", str(startup_obj)])

    elf = out / f"{name}.elf"
    map_file = out / f"{name}.map"
    link = [str(tc.gcc), *CPU_FLAGS, *LINK_FLAGS, f"-T{bfiles['linker_script']}",
            f"-Wl,-Map={map_file}", str(startup_obj), *map(str, objects), *LINK_LIBS,
            "-o", str(elf)]
    _build(link)
    return BuildResult(elf=elf, objects=tuple(objects), su_files=tuple(su_files),
                       map_file=map_file, compile_command=tuple(first_cmd),
                       link_command=tuple(link), elf_sizes=elf_sizes(elf, tc))


def _function_ranges(elf: Path, nm: Path, names: Sequence[str] | None = None
                     ) -> dict[str, tuple[int, int]]:
    """``{name: (start, stop)}`` of the ELF's functions (all of them when ``names`` is None)."""
    out = run_tool([str(nm), "-S", "--defined-only", str(elf)])
    ranges: dict[str, tuple[int, int]] = {}
    for line in out.splitlines():
        parts = line.split()
        if (len(parts) == 4 and parts[2] in "Tt"
                and (names is None or parts[3] in names)):
            start = int(parts[0], 16) & ~1
            ranges[parts[3]] = (start, start + int(parts[1], 16))
    return ranges


_TRACE_PC = re.compile(r"^Trace \d+: \S+ \[[0-9a-fA-F]+/([0-9a-fA-F]+)/")


def _regions(trace: Iterable[str], begin: tuple[int, int], end_entry: int):
    """The program counters of each measured region: yields one list per region, the
    instructions after ``stt_measure_begin`` returned and before ``stt_measure_end`` was
    entered, the ``bl stt_measure_end`` excluded."""
    current: list[int] | None = None
    started = False
    b0, b1 = begin
    for line in trace:
        m = _TRACE_PC.match(line)
        if m is None:
            continue
        pc = int(m.group(1), 16)
        if pc == end_entry:
            if current is not None:
                yield current[:-1]
            current = None
            continue
        if pc == b0:
            current, started = [], False
            continue
        if current is None:
            continue
        if not started and b0 <= pc < b1:
            continue
        started = True
        current.append(pc)


def count_region_instructions(trace: Iterable[str], begin: tuple[int, int],
                              end_entry: int) -> list[int]:
    """Count instructions per measured region in a QEMU ``-d exec`` trace.

    Parameters
    ----------
    trace : iterable of str
        Lines of a trace made with ``-singlestep -d exec,nochain`` (one line per
        executed instruction).
    begin : tuple of int
        ``[start, stop)`` addresses of ``stt_measure_begin``.
    end_entry : int
        Address of ``stt_measure_end``.

    Returns
    -------
    list of int
        For each region, the instructions executed after ``stt_measure_begin``
        returned and before ``stt_measure_end`` was entered, excluding the
        ``bl stt_measure_end`` instruction.
    """
    return [len(pcs) for pcs in _regions(trace, begin, end_entry)]


def profile_regions(trace: Iterable[str], begin: tuple[int, int], end_entry: int,
                    functions: Mapping[str, tuple[int, int]]) -> list[dict[str, list[int]]]:
    """Per measured region, the instructions of each function (exclusive) and its entries.

    Parameters
    ----------
    trace, begin, end_entry
        As :func:`count_region_instructions`.
    functions : mapping
        ``{name: (start, stop)}`` address ranges (``nm -S``); an instruction outside every
        range counts under ``"?"``.

    Returns
    -------
    list of dict
        For each region, ``{name: [instructions, entries]}``: the instructions executed
        inside the function's range (callees excluded; the region's instructions split
        by function, so they add up to :func:`count_region_instructions`'s count) and
        how many times its first instruction was executed (its calls, unless it loops
        back to its first instruction).
    """
    ranges = sorted((start, stop, name) for name, (start, stop) in functions.items())
    starts = [start for start, _, _ in ranges]
    out: list[dict[str, list[int]]] = []
    for pcs in _regions(trace, begin, end_entry):
        region: dict[str, list[int]] = {}
        for pc in pcs:
            i = bisect.bisect_right(starts, pc) - 1
            inside = i >= 0 and pc < ranges[i][1]
            entry = region.setdefault(ranges[i][2] if inside else "?", [0, 0])
            entry[0] += 1
            if inside and pc == ranges[i][0]:
                entry[1] += 1
        out.append(region)
    return out


def qemu_command(elf: Path, *, trace_file: Path | None = None,
                 qemu: str = "qemu-system-arm") -> list[str]:
    """The QEMU command line that runs ``elf`` (optionally with an exec trace).

    Parameters
    ----------
    elf : Path
        Program built by :func:`build_elf`.
    trace_file : Path, optional
        Write a one-line-per-instruction execution trace there.
    qemu : str, optional
        QEMU executable.

    Returns
    -------
    list of str
        The command.
    """
    cmd = [qemu, "-machine", board.MACHINE, "-nographic", "-monitor", "none",
           "-serial", "none", "-semihosting-config", "enable=on,target=native"]
    if trace_file is not None:
        cmd += ["-singlestep", "-d", "exec,nochain", "-D", str(trace_file)]
    return cmd + ["-kernel", str(elf)]


def run_qemu(elf: Path, timeout: float = 60.0, *,
             count_instructions: bool = False) -> RunResult:
    """Run a program under ``qemu-system-arm -machine mps2-an386``.

    Parameters
    ----------
    elf : Path
        Program built by :func:`build_elf`.
    timeout : float, optional
        Seconds before QEMU is killed (``RunResult.timed_out``).
    count_instructions : bool, optional
        Count the instructions of each region marked by
        ``stt_measure_begin()``/``stt_measure_end()`` (slower: every
        instruction is traced to a temporary file).

    Returns
    -------
    RunResult
        Standard output, exit status, instruction counts.

    Raises
    ------
    MissingTool
        If QEMU is not installed.
    RunError
        If counting was requested and the program has no measured-region
        markers.
    """
    tc = find_toolchain(need_qemu=True)
    assert tc.qemu is not None
    elf = Path(elf)
    with tempfile.TemporaryDirectory(prefix="stt-qemu-") as tmp:
        trace = Path(tmp) / "exec.log" if count_instructions else None
        cmd = qemu_command(elf, trace_file=trace, qemu=str(tc.qemu))
        try:
            proc = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True,
                                  timeout=timeout, check=False)
        except subprocess.TimeoutExpired as exc:
            out = exc.stdout.decode(errors="replace") if exc.stdout else ""
            err = exc.stderr.decode(errors="replace") if exc.stderr else ""
            return RunResult(out, None, None, timed_out=True, stderr=err, command=tuple(cmd))
        stdout = proc.stdout.decode(errors="replace")
        stderr = proc.stderr.decode(errors="replace")
        if any(line.startswith("qemu-system-arm:") and "warning" not in line
               for line in stderr.splitlines()):
            raise RunError(f"{' '.join(cmd)}: {stderr}")
        profile = None
        if trace is not None:
            ranges = _function_ranges(elf, tc.nm)
            if "stt_measure_begin" not in ranges or "stt_measure_end" not in ranges:
                raise RunError(f"{elf}: no stt_measure_begin/stt_measure_end to count between")
            with open(trace, encoding="utf-8", errors="replace") as fh:
                profile = profile_regions(fh, ranges["stt_measure_begin"],
                                          ranges["stt_measure_end"][0], ranges)
    counts = None if profile is None else [sum(v[0] for v in r.values()) for r in profile]
    return RunResult(stdout, proc.returncode, counts, stderr=stderr, command=tuple(cmd),
                     functions=profile)


def run_checked(elf: Path, timeout: float, **kw) -> RunResult:
    """:func:`run_qemu`, with a timeout or a fault on the target raised.

    Parameters
    ----------
    elf : Path
        Program built by :func:`build_elf`.
    timeout : float
        Seconds before QEMU is killed.
    **kw
        Passed to :func:`run_qemu` (``count_instructions``).

    Returns
    -------
    RunResult

    Raises
    ------
    ToolchainError
        QEMU timed out, or the program faulted (the startup code's message).
    """
    res = run_qemu(elf, timeout=timeout, **kw)
    if res.timed_out:
        raise ToolchainError(f"{Path(elf).name}: QEMU timed out after {timeout:g} s")
    if res.exit_code == board.FAULT_EXIT_STATUS:
        raise ToolchainError(f"{Path(elf).name}: fault on the target:\n{res.stderr}")
    return res
