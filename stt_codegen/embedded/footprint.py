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
from stt_codegen.errors import SttError

_CALL_RELOCS = ("R_ARM_THM_CALL", "R_ARM_THM_JUMP24", "R_ARM_THM_JUMP19", "R_ARM_CALL",
                "R_ARM_JUMP24")


class FootprintError(SttError):
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
