"""Locate the cross toolchain and the emulator used by the embedded harness.

Every tool is looked up on ``PATH`` with :func:`stt_codegen.system.find_tool`; a
missing tool raises :class:`~stt_codegen.system.MissingTool`, which names the Debian
package that provides it, so a caller (or a test) can tell the user exactly what to
install.
"""

from __future__ import annotations

import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from stt_codegen import system
from stt_codegen.errors import ToolchainError
from stt_codegen.system import MissingTool

__all__ = ["BUILD_TOOLS", "DEBIAN_PACKAGES", "MissingTool", "RUN_TOOLS", "ToolError", "Toolchain",
           "find_tool", "find_toolchain", "missing_message", "missing_tools", "run_tool"]

#: Tool name -> Debian package that provides it.
DEBIAN_PACKAGES: dict[str, str] = {
    "arm-none-eabi-gcc": "gcc-arm-none-eabi",
    "arm-none-eabi-size": "binutils-arm-none-eabi",
    "arm-none-eabi-objdump": "binutils-arm-none-eabi",
    "arm-none-eabi-nm": "binutils-arm-none-eabi",
    "qemu-system-arm": "qemu-system-arm",
    # Not an executable: newlib's semihosting (rdimon) specs, found through gcc.
    "rdimon.specs": "libnewlib-arm-none-eabi",
}

#: Tools needed to build and measure (no emulator).
BUILD_TOOLS: tuple[str, ...] = (
    "arm-none-eabi-gcc", "arm-none-eabi-size", "arm-none-eabi-objdump",
    "arm-none-eabi-nm", "rdimon.specs",
)
#: Tools needed to run a program.
RUN_TOOLS: tuple[str, ...] = ("qemu-system-arm", "arm-none-eabi-nm")


class ToolError(ToolchainError):
    """A tool (compiler, linker, binutils) failed.

    Parameters
    ----------
    command : sequence of str
        The command that failed.
    output : str
        Its standard error and output.
    """

    def __init__(self, command: Sequence[str], output: str) -> None:
        self.command = list(command)
        self.output = output
        super().__init__(f"{' '.join(command)} failed:\n{output}")


@dataclass(frozen=True)
class Toolchain:
    """Absolute paths of the tools, as found on this machine.

    Attributes
    ----------
    gcc, size, objdump, nm : Path
        The ``arm-none-eabi-`` binaries.
    qemu : Path or None
        ``qemu-system-arm``; ``None`` when only building was requested.
    """

    gcc: Path
    size: Path
    objdump: Path
    nm: Path
    qemu: Path | None


def run_tool(cmd: Sequence[str], cwd: Path | None = None) -> str:
    """Run a tool; return its standard output.

    Parameters
    ----------
    cmd : sequence of str
        Command line.
    cwd : Path, optional
        Working directory.

    Returns
    -------
    str
        Standard output.

    Raises
    ------
    ToolError
        If the command exits with a non-zero status.
    """
    proc = subprocess.run(list(cmd), capture_output=True, text=True, cwd=cwd, check=False)
    if proc.returncode != 0:
        raise ToolError(cmd, proc.stderr + proc.stdout)
    return proc.stdout


def _has_newlib(gcc: str) -> bool:
    try:
        out = subprocess.run([gcc, "-print-file-name=rdimon.specs"], capture_output=True,
                             text=True, timeout=30, check=False).stdout.strip()
    except OSError:
        return False
    return out != "rdimon.specs" and Path(out).is_file()


def find_tool(tool: str) -> Path:
    """Return the path of one tool or raise :class:`MissingTool`.

    Parameters
    ----------
    tool : str
        A key of :data:`DEBIAN_PACKAGES`.

    Returns
    -------
    Path
        Absolute path of the executable (of the specs file for ``rdimon.specs``).

    Raises
    ------
    MissingTool
        If the tool is not installed.
    """
    package = DEBIAN_PACKAGES[tool]
    if tool == "rdimon.specs":
        try:
            gcc = system.find_tool("arm-none-eabi-gcc", package=package)
        except MissingTool:
            raise MissingTool(tool, package) from None
        if not _has_newlib(gcc):
            raise MissingTool(tool, package)
        return Path(subprocess.run([gcc, "-print-file-name=rdimon.specs"],
                                   capture_output=True, text=True, check=True).stdout.strip())
    return Path(system.find_tool(tool, package=package))


def missing_tools(tools: tuple[str, ...] = BUILD_TOOLS + RUN_TOOLS) -> list[MissingTool]:
    """All missing tools among ``tools`` (empty list when everything is there).

    Parameters
    ----------
    tools : tuple of str
        Keys of :data:`DEBIAN_PACKAGES`.

    Returns
    -------
    list of MissingTool
        One error per missing tool, in the order given.
    """
    missing: dict[str, MissingTool] = {}
    for tool in dict.fromkeys(tools):
        try:
            find_tool(tool)
        except MissingTool as err:
            missing.setdefault(err.tool, err)
    return list(missing.values())


def missing_message(tools: tuple[str, ...] = BUILD_TOOLS + RUN_TOOLS) -> str | None:
    """One line naming the missing tools and the Debian packages to install.

    Parameters
    ----------
    tools : tuple of str
        Keys of :data:`DEBIAN_PACKAGES`.

    Returns
    -------
    str or None
        ``None`` when nothing is missing.
    """
    missing = missing_tools(tools)
    if not missing:
        return None
    names = ", ".join(m.tool for m in missing)
    packages = " ".join(dict.fromkeys(m.package for m in missing))
    return f"missing {names}; install the Debian packages: apt-get install -y {packages}"


def find_toolchain(*, need_qemu: bool = True) -> Toolchain:
    """Locate every tool, raising :class:`MissingTool` for the first missing one.

    Parameters
    ----------
    need_qemu : bool, optional
        Also require ``qemu-system-arm`` (default ``True``).

    Returns
    -------
    Toolchain
        Paths of the tools.

    Raises
    ------
    MissingTool
        If a tool is not installed.
    """
    for tool in BUILD_TOOLS:
        find_tool(tool)
    return Toolchain(
        gcc=find_tool("arm-none-eabi-gcc"),
        size=find_tool("arm-none-eabi-size"),
        objdump=find_tool("arm-none-eabi-objdump"),
        nm=find_tool("arm-none-eabi-nm"),
        qemu=find_tool("qemu-system-arm") if need_qemu else None,
    )
