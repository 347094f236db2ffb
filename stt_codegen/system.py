"""The toolkit's contact with the host system: durable and atomic file writes, tool lookup.

One way to do each, used by every package (the bottom layer: imports nothing of the
package but :mod:`stt_codegen.errors`):

* :func:`write_durably` creates a file and flushes it to the disk (``fsync``);
  :func:`atomic_write` writes a temporary file beside the target, flushes it and moves
  it into place with ``os.replace``: readers see the old file or the new one, never half
  of one, even if the process is killed.
* :func:`find_tool` looks an executable up on ``PATH`` (``shutil.which``) and raises
  :class:`MissingTool`, which names the Debian package to install.
"""

from __future__ import annotations

import os
import secrets
import shutil
from collections.abc import Callable
from pathlib import Path

from .errors import SpecError, ToolchainError


class MissingTool(ToolchainError):
    """A tool the toolkit drives is not installed (command line: exit code 3).

    Parameters
    ----------
    tool : str
        Name of the missing executable (or file, e.g. ``"rdimon.specs"``).
    package : str
        Debian package that provides it.
    """

    def __init__(self, tool: str, package: str) -> None:
        self.tool = tool
        self.package = package
        super().__init__(
            f"{tool} not found; install the Debian package {package} "
            f"(apt-get install -y {package})")


def find_tool(*names: str, package: str) -> str:
    """Path of the first of ``names`` found on ``PATH``.

    Parameters
    ----------
    *names : str
        Executables, in order of preference (e.g. ``"gcc", "cc"``).
    package : str
        Debian package that provides the first one, for the error message.

    Returns
    -------
    str
        What ``shutil.which`` returns: the executable's path.

    Raises
    ------
    MissingTool
        None of ``names`` is on ``PATH`` (it names the first one and ``package``).
    """
    for name in names:
        found = shutil.which(name)
        if found:
            return found
    raise MissingTool(names[0], package)


def fsync_path(path: str | Path) -> None:
    """Flush a file's or a folder's content (a folder: its entries) to the disk.

    Parameters
    ----------
    path : str or pathlib.Path
        An existing file or folder.

    Raises
    ------
    OSError
        ``path`` cannot be opened or flushed.
    """
    fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_durably(path: str | Path, data: bytes) -> None:
    """Create the file ``path`` (it must not exist) holding ``data``, flushed to the disk.

    Parameters
    ----------
    path : str or pathlib.Path
        The file to create; its folder must exist.
    data : bytes
        The whole content of the file.

    Raises
    ------
    FileExistsError
        ``path`` exists.
    OSError
        The write failed.
    """
    with open(path, "xb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())


def atomic_write(path: str | Path, data: bytes | Callable[[Path], None],
                 field: str = "output") -> None:
    """Replace ``path`` with new content atomically: the old file or the new one, whole.

    The content goes to a temporary file beside ``path`` (created with mode 0666 and the
    umask, as any new file), is flushed (``fsync``), then moved onto ``path`` with
    ``os.replace``; on any error the temporary file is removed and ``path`` is unchanged.

    Parameters
    ----------
    path : str or path
        The file; its folder must exist.
    data : bytes or callable
        The content, or a function that writes it to the path it is given (e.g. a
        plot's ``savefig``).
    field : str
        Name of the parameter ``path`` came from, for the :class:`SpecError`.

    Raises
    ------
    SpecError
        The folder of ``path`` does not exist (field ``field``).
    OSError
        The write failed.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise SpecError(field, f"folder {str(folder)!r} does not exist")
    tmp = folder / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}{path.suffix}"
    try:
        if callable(data):
            # not mkstemp: its 0600 would stay on the file; O_EXCL with 0666 lets the umask decide
            os.close(os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
            data(tmp)
            fsync_path(tmp)
        else:
            write_durably(tmp, data)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    fsync_path(folder)


__all__ = ["MissingTool", "atomic_write", "find_tool", "fsync_path", "write_durably"]
