"""Static memory footprint of object files: flash, RAM and worst-case stack.

* Sizes come from ``arm-none-eabi-size -A`` on the given objects (so only the
  controller's own code is counted, not newlib or the test program): ``.text*``
  and ``.ARM.ex*`` are code, ``.rodata*`` constants, ``.data*`` initialised and
  ``.bss*`` zero-initialised variables. ``flash_bytes = text + rodata + data``
  (the initial values of ``.data`` are stored in flash) and
  ``ram_bytes = data + bss``. Objects are measured before ``--gc-sections``, so
  unused functions count too (an upper bound).
* Stack: the frame sizes of ``-fstack-usage`` (``.su`` files) are summed along
  the call graph, found from the call/branch relocations
  (``R_ARM_THM_CALL``/``R_ARM_THM_JUMP24``/``R_ARM_THM_JUMP19``) in
  ``arm-none-eabi-objdump -dr`` of the objects (compiled with
  ``-ffunction-sections``, so every call between functions has a relocation).
  The worst case over all paths from ``entry`` is a *static* bound: callees
  without a ``.su`` entry (libm, libgcc) count as 0 and are listed in
  ``Footprint.unresolved``; calls through function pointers are not seen.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from stt_codegen.embedded.toolchain import find_toolchain, run_tool
from stt_codegen.errors import ToolchainError

__all__ = ["Footprint", "FootprintError", "elf_stack_bound", "linked_sizes", "measure",
           "worst_stack"]

_CALL_RELOCS = ("R_ARM_THM_CALL", "R_ARM_THM_JUMP24", "R_ARM_THM_JUMP19", "R_ARM_CALL",
                "R_ARM_JUMP24")


class FootprintError(ToolchainError):
    """The stack bound cannot be computed (unknown entry, recursion)."""


@dataclass(frozen=True)
class Footprint:
    """Memory footprint of a set of object files.

    Attributes
    ----------
    text, rodata, data, bss : int
        Section totals in bytes.
    flash_bytes : int
        ``text + rodata + data``.
    ram_bytes : int
        ``data + bss`` (static RAM, stack excluded).
    stack_bytes : int or None
        Static worst-case stack of ``entry`` and its callees (``None`` without
        ``entry``).
    stack_chain : tuple of str
        The call chain that attains ``stack_bytes``, ``entry`` first.
    stack_is_static : bool
        Always ``True``: the bound comes from ``-fstack-usage``, not a run.
    stack_dynamic : tuple of str
        Functions on the graph whose ``.su`` qualifier is ``dynamic`` (frame
        size not a compile-time constant: the bound is not safe for them).
    unresolved : tuple of str
        Callees reachable from ``entry`` with no ``.su`` entry (counted as 0).
    frames : dict
        Frame size of every function in the ``.su`` files.
    """

    text: int
    rodata: int
    data: int
    bss: int
    flash_bytes: int
    ram_bytes: int
    stack_bytes: int | None
    stack_chain: tuple[str, ...] = ()
    stack_is_static: bool = True
    stack_dynamic: tuple[str, ...] = ()
    unresolved: tuple[str, ...] = ()
    frames: dict[str, int] = field(default_factory=dict)


def section_sizes(objects: Sequence[Path]) -> dict[str, int]:
    """Sum ``text``, ``rodata``, ``data``, ``bss`` over object files.

    Parameters
    ----------
    objects : sequence of Path
        ELF relocatable objects.

    Returns
    -------
    dict
        Byte totals per class.
    """
    tc = find_toolchain(need_qemu=False)
    totals = {"text": 0, "rodata": 0, "data": 0, "bss": 0}
    for obj in objects:
        for line in run_tool([str(tc.size), "-A", "-d", str(obj)]).splitlines():
            parts = line.split()
            if len(parts) != 3 or not parts[1].isdigit():
                continue
            name, size = parts[0], int(parts[1])
            if name.startswith((".text", ".ARM.exidx", ".ARM.extab")):
                totals["text"] += size
            elif name.startswith(".rodata"):
                totals["rodata"] += size
            elif name.startswith(".data"):
                totals["data"] += size
            elif name.startswith(".bss") or name == "COMMON":
                totals["bss"] += size
    return totals


def read_stack_usage(su_files: Sequence[Path]) -> tuple[dict[str, int], set[str]]:
    """Parse ``-fstack-usage`` files.

    Parameters
    ----------
    su_files : sequence of Path
        ``.su`` files (lines ``file:line:col:function<TAB>bytes<TAB>qualifiers``).

    Returns
    -------
    frames : dict
        Function name -> frame bytes (the largest if a static name repeats).
    dynamic : set of str
        Functions whose qualifier contains ``dynamic``.
    """
    frames: dict[str, int] = {}
    dynamic: set[str] = set()
    for su in su_files:
        for line in Path(su).read_text().splitlines():
            parts = line.split("\t")
            if len(parts) < 3:
                continue
            name = parts[0].rsplit(":", 1)[-1]
            frames[name] = max(frames.get(name, 0), int(parts[1]))
            if "dynamic" in parts[2]:
                dynamic.add(name)
    return frames, dynamic


_FUNC = re.compile(r"^[0-9a-fA-F]+ <([^>]+)>:$")
_RELOC = re.compile(r"^\s*[0-9a-fA-F]+:\s+(R_ARM_\w+)\s+(\S+)")


def call_graph(objects: Sequence[Path]) -> dict[str, set[str]]:
    """Direct calls (and tail calls) between functions, from relocations.

    Parameters
    ----------
    objects : sequence of Path
        Objects compiled with ``-ffunction-sections``.

    Returns
    -------
    dict
        Caller -> set of callee symbol names.
    """
    tc = find_toolchain(need_qemu=False)
    graph: dict[str, set[str]] = {}
    for obj in objects:
        current: str | None = None
        for line in run_tool([str(tc.objdump), "-dr", str(obj)]).splitlines():
            m = _FUNC.match(line)
            if m:
                current = m.group(1)
                graph.setdefault(current, set())
                continue
            r = _RELOC.match(line)
            if r and current is not None and r.group(1) in _CALL_RELOCS:
                callee = r.group(2).split("+")[0]
                if callee != current:
                    graph[current].add(callee)
    return graph


def worst_stack(entry: str, frames: dict[str, int],
                graph: dict[str, set[str]]) -> tuple[int, tuple[str, ...], tuple[str, ...]]:
    """Worst-case stack depth from ``entry`` (sum of frames along the deepest path).

    Parameters
    ----------
    entry : str
        Root function.
    frames : dict
        Frame bytes per function.
    graph : dict
        Caller -> callees.

    Returns
    -------
    bytes : int
        Worst case.
    chain : tuple of str
        The path attaining it.
    unresolved : tuple of str
        Reached callees without a frame size (counted as 0).

    Raises
    ------
    FootprintError
        If ``entry`` is unknown or the graph is recursive.
    """
    if entry not in frames and entry not in graph:
        raise FootprintError(f"entry function {entry!r} not found in the objects")
    memo: dict[str, tuple[int, tuple[str, ...]]] = {}
    unresolved: set[str] = set()

    def visit(fn: str, path: tuple[str, ...]) -> tuple[int, tuple[str, ...]]:
        if fn in path:
            raise FootprintError(f"recursion: {' -> '.join(path + (fn,))}; no static bound")
        if fn in memo:
            return memo[fn]
        if fn not in frames:
            unresolved.add(fn)
        best = (0, ())
        for callee in sorted(graph.get(fn, ())):
            best = max(best, visit(callee, path + (fn,)), key=lambda b: b[0])
        result = (frames.get(fn, 0) + best[0], (fn,) + best[1])
        memo[fn] = result
        return result

    total, chain = visit(entry, ())
    return total, chain, tuple(sorted(unresolved))


def measure(objects: Sequence[Path], su_files: Sequence[Path] = (),
            entry: str | None = None) -> Footprint:
    """Flash, RAM and static worst-case stack of the given objects.

    Parameters
    ----------
    objects : sequence of Path
        The controller's object files only (not the test program's).
    su_files : sequence of Path, optional
        Their ``-fstack-usage`` files; default: ``<object>.su`` next to each
        object when it exists.
    entry : str, optional
        Function whose worst-case stack is wanted (e.g. the controller step).

    Returns
    -------
    Footprint
        Sizes in bytes; see the module docstring for what is counted.

    Raises
    ------
    MissingTool
        If binutils for ARM are not installed.
    FootprintError
        If ``entry`` is not found or recursive.
    """
    objects = [Path(o) for o in objects]
    if not su_files:
        su_files = [o.with_suffix(".su") for o in objects if o.with_suffix(".su").exists()]
    sizes = section_sizes(objects)
    frames, dynamic = read_stack_usage(su_files)
    stack: int | None = None
    chain: tuple[str, ...] = ()
    unresolved: tuple[str, ...] = ()
    dyn: tuple[str, ...] = ()
    if entry is not None:
        graph = call_graph(objects)
        stack, chain, unresolved = worst_stack(entry, frames, graph)
        reach: set[str] = set()
        todo = [entry]
        while todo:
            fn = todo.pop()
            if fn not in reach:
                reach.add(fn)
                todo.extend(graph.get(fn, ()))
        dyn = tuple(sorted(reach & dynamic))
    return Footprint(
        text=sizes["text"], rodata=sizes["rodata"], data=sizes["data"], bss=sizes["bss"],
        flash_bytes=sizes["text"] + sizes["rodata"] + sizes["data"],
        ram_bytes=sizes["data"] + sizes["bss"],
        stack_bytes=stack, stack_chain=chain, stack_dynamic=dyn, unresolved=unresolved,
        frames=frames)


# ---------------------------------------------------------------- linked ELF

_ELF_FUNC = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
_ELF_INSN = re.compile(r"^\s*([0-9a-f]+):\s+(?:[0-9a-f]{4}(?: [0-9a-f]{4})?\s+)?(\S+)\s*(.*)$")
_REGLIST = re.compile(r"\{([^}]*)\}")
_SP_IMM = re.compile(r"^sp,\s*(?:sp,\s*)?#(\d+)")
_TARGET = re.compile(r"^[0-9a-f]+ <([^>+]+)>$")


def _reg_count(text: str) -> tuple[int, int]:
    """(number of registers, bytes each) of a register list ``{r4-r7, lr}``/``{s16-s19}``/``{d8}``."""
    m = _REGLIST.search(text)
    if not m:
        return 0, 4
    count, size = 0, 4
    for part in m.group(1).split(","):
        part = part.strip()
        if part.startswith("d"):
            size = 8
        if "-" in part:
            a, b = part.split("-")
            count += int(re.sub(r"\D", "", b)) - int(re.sub(r"\D", "", a)) + 1
        elif part:
            count += 1
    return count, size


def elf_functions(elf: Path) -> tuple[dict[str, int], dict[str, set[str]]]:
    """Frame bytes and direct callees of every function of a linked ELF, from its code.

    The frame of a function is the largest stack depth its instructions reach when read
    in address order (``push``/``stmdb sp!``/``vpush``/``sub sp`` add, ``pop``/``ldmia
    sp!``/``vpop``/``add sp`` remove): a bound for the straight-line prologue/epilogue
    code compilers emit (no ``alloca``, no variable ``sub sp, rN``: those raise
    :class:`FootprintError`). Callees are the targets of ``bl``/``blx`` and of branches
    (``b``, ``b.w``, ``bcc.w``) to another function's first address (tail calls).
    """
    tc = find_toolchain(need_qemu=False)
    text = run_tool([str(tc.objdump), "-d", "--no-show-raw-insn", str(elf)])
    frames: dict[str, int] = {}
    graph: dict[str, set[str]] = {}
    starts: dict[str, str] = {}
    current = None
    depth = peak = 0
    pending: list[tuple[str, str, str]] = []
    for line in text.splitlines():
        m = _ELF_FUNC.match(line)
        if m:
            if current is not None:
                frames[current] = peak
            current = m.group(2)
            starts[current] = m.group(1).lstrip("0") or "0"
            graph.setdefault(current, set())
            depth = peak = 0
            continue
        if current is None:
            continue
        i = _ELF_INSN.match(line)
        if not i:
            continue
        op, args = i.group(2), i.group(3).split(";")[0].strip()
        base = op.split(".")[0]
        if base in ("push", "vpush") or (base.startswith("stmdb") and args.startswith("sp!")):
            k, size = _reg_count(args)
            depth += k * size
        elif base in ("pop", "vpop") or (base.startswith("ldmia") and args.startswith("sp!")):
            k, size = _reg_count(args)
            depth -= k * size
        elif base in ("sub", "subw") and args.startswith("sp,"):
            s = _SP_IMM.match(args)
            if not s:
                raise FootprintError(f"{current}: variable stack adjustment '{op} {args}'")
            depth += int(s.group(1))
        elif base in ("add", "addw") and args.startswith("sp,") and _SP_IMM.match(args):
            depth -= int(_SP_IMM.match(args).group(1))
        elif base.startswith("str") and "[sp, #-" in args and args.endswith("]!"):
            depth += int(re.search(r"#-(\d+)", args).group(1))
        peak = max(peak, depth)
        if base in ("bl", "blx") or base.startswith("b"):
            t = _TARGET.match(args)
            if t:
                pending.append((current, base, t.group(1)))
    if current is not None:
        frames[current] = peak
    for caller, base, target in pending:
        if target == caller:
            continue
        if base in ("bl", "blx") or target in starts:
            graph[caller].add(target)
    return frames, graph


def elf_stack_bound(elf: Path, entry: str) -> dict:
    """Static worst-case stack of ``entry`` in a linked ELF, library code included.

    Parameters
    ----------
    elf : pathlib.Path
        The linked program.
    entry : str
        The function whose worst-case stack is bounded (e.g. the controller's ``step``).

    Returns
    -------
    dict
        ``bytes``, ``chain`` (the deepest call path) and ``frames`` along it.

    Raises
    ------
    FootprintError
        Unknown entry, recursion, or a variable stack adjustment on the way.
    """
    frames, graph = elf_functions(Path(elf))
    total, chain, _ = worst_stack(entry, frames, graph)
    return {"bytes": total, "chain": chain, "frames": {f: frames.get(f, 0) for f in chain}}


def linked_sizes(map_file: Path, obj: Path) -> dict[str, int]:
    """Bytes of ``obj``'s input sections the linker kept (after ``--gc-sections``).

    Parsed from the GNU ld map file's memory map (the part after "Linker script and
    memory map"; discarded sections are listed before it).

    Parameters
    ----------
    map_file : pathlib.Path
        The GNU ld map file (``-Map``).
    obj : pathlib.Path
        The object file, as the map file names it.

    Returns
    -------
    dict of str to int
        Bytes of ``text`` (``.text*``, ``.ARM.ex*``), ``rodata``, ``data`` and ``bss``.
    """
    text = Path(map_file).read_text(errors="replace")
    start = text.find("Linker script and memory map")
    body = text[start:] if start >= 0 else text
    sizes = {"text": 0, "rodata": 0, "data": 0, "bss": 0}
    name = None
    want = str(obj)
    rx = re.compile(r"^\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S+)$")
    for line in body.splitlines():
        m = re.match(r"^ (\.\S+)(.*)$", line)
        rest = line
        if m:
            name = m.group(1)
            rest = m.group(2)
            if not rest.strip():
                continue
        r = rx.match(rest if m else line)
        if r and name and r.group(3) == want:
            size = int(r.group(2), 16)
            if name.startswith(".text") or name.startswith(".ARM.ex"):
                sizes["text"] += size
            elif name.startswith(".rodata"):
                sizes["rodata"] += size
            elif name.startswith(".data"):
                sizes["data"] += size
            elif name.startswith(".bss"):
                sizes["bss"] += size
        if not m:
            name = name if r is None else None
    return sizes
