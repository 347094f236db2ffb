"""Writing a generation into ``-o DIR``: only DIR, only over our own files, whole or not at all.

Rules (:func:`write_generation`; the user's view is in docs/codegen.md, "The output folder"):

* ``DIR``'s parent must exist; ``DIR`` is created if missing. A symlink to a folder is
  followed (``DIR`` is then the folder it points to); a dangling one is refused.
* If ``DIR`` exists it must be empty or hold a ``manifest.json`` of ours; every entry of
  ``DIR`` must be a regular file (not a symlink) that manifest lists (or the manifest
  itself), with the SHA-256 the manifest records (a file edited since it was generated
  is not ours any more), or a build product of the generated build files (below).
  Anything else (a foreign file, a folder, a symlink, a manifest of another tool, a
  manifest naming a path rather than a flat file name) is refused with a
  :class:`SpecError` and nothing is written.
* Build products: with ``Makefile`` listed, ``P.o`` and ``P_selftest`` (regular files;
  ``P`` from the listed ``P.c`` and ``P_selftest.c``); with ``CMakeLists.txt`` listed,
  the folder ``build`` if CMake made it for this folder (its ``CMakeCache.txt`` names
  ``DIR`` as the source folder: ``cmake -S . -B build``, the command the file documents).
  They are moved into the new generation if its build files produce the same names
  (``make`` and ``cmake --build`` then rebuild from the newer sources), else discarded
  with the old generation.
* One generation at a time: a ``flock`` on ``.DIR.stt-codegen-lock`` beside ``DIR`` is
  held from the check of ``DIR`` to the switch; another writer waits up to
  ``lock_timeout`` seconds, then gives up with a :class:`SpecError`. The lock file is
  removed by its holder (a waiter that locked a removed file retries on the new one).
* Atomic switch: the new generation is written (and fsync'ed) into a sibling
  ``.DIR.stt-codegen-tmp-XXXXXXXX``, then swapped with ``DIR`` in one
  ``renameat2(RENAME_EXCHANGE)`` (Linux); the old generation, now in the sibling, is
  removed. Where the exchange is not available: ``DIR`` is renamed to
  ``.DIR.stt-codegen-old-XXXXXXXX``, the new folder to ``DIR``, the old one removed.
* Recovery: under the lock, before anything else, a missing ``DIR`` with one
  ``.DIR.stt-codegen-old-*`` sibling (a writer killed between the two renames) is
  renamed back, and every other ``.DIR.stt-codegen-tmp-*``/``-old-*`` sibling (left by a
  killed writer: no live writer holds the lock) is removed. A killed writer therefore
  leaves ``DIR`` as the old or the new generation, whole.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import hashlib
import json
import os
import re
import secrets
import shutil
import time
from collections.abc import Iterator
from pathlib import Path

from ..errors import SpecError
from ..system import fsync_path, write_durably
from .generate import GENERATOR, MANIFEST

__all__ = ["LOCK_TIMEOUT", "build_products", "write_generation"]

#: Seconds a writer waits for another writer of the same folder before giving up.
LOCK_TIMEOUT = 60.0
_LOCK = ".stt-codegen-lock"
_TMP = ".stt-codegen-tmp-"
_OLD = ".stt-codegen-old-"
_LEGACY_TMP = ".stt-codegen-tmp-"   # temporary folder inside DIR of versions before the switch
_BUILD = "build"


def _flat_name(name) -> bool:
    return (isinstance(name, str) and bool(name) and "/" not in name and "\\" not in name
            and "\0" not in name and name not in (".", "..") and not name.startswith("."))


def _file_sha256(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def build_products(names) -> dict[str, str]:
    """What the generated build files among ``names`` produce: name -> ``"file"``/``"dir"``.

    ``Makefile``: ``P.o`` and ``P_selftest``; ``CMakeLists.txt``: the build folder
    ``build`` (``cmake -S . -B build``). ``P`` is the prefix of the listed ``P.c`` and
    ``P_selftest.c``.

    Parameters
    ----------
    names : iterable of str
        File names of one generation.

    Returns
    -------
    dict of str to str
        Product name (relative to the output folder) to ``"file"`` or ``"dir"``.
    """
    names = set(names)
    prefixes = [n[:-len("_selftest.c")] for n in names
                if n.endswith("_selftest.c") and n[:-len("_selftest.c")] + ".c" in names]
    products = {}
    if "Makefile" in names:
        for p in prefixes:
            products[f"{p}.o"] = products[f"{p}_selftest"] = "file"
    if "CMakeLists.txt" in names:
        products[_BUILD] = "dir"
    return products


def _is_our_cmake_build(folder: Path, source: Path) -> bool:
    """``folder`` is a CMake build tree configured from ``source``."""
    if folder.is_symlink() or not folder.is_dir():
        return False
    try:
        cache = (folder / "CMakeCache.txt").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return False
    found = re.search(r"^CMAKE_HOME_DIRECTORY:INTERNAL=(.*)$", cache, flags=re.M)
    return bool(found) and os.path.realpath(found.group(1)) == os.path.realpath(source)


def _inspect(out_dir: Path, shown: str, check_hashes: bool) -> list[str]:
    """Build products among the entries of ``out_dir``, after checking every entry is ours.

    Raises
    ------
    SpecError
        ``out_dir`` holds entries that are not ours (field ``out_dir``).
    """
    entries = sorted(p.name for p in out_dir.iterdir()
                     if not (p.name.startswith(_LEGACY_TMP) and p.is_dir()
                             and not p.is_symlink()))
    if not entries:
        return []
    path = out_dir / MANIFEST
    try:
        if path.is_symlink():
            raise ValueError("symlink")
        data = json.loads(path.read_text(encoding="utf-8"))
        files = data["files"] if data.get("generator") == GENERATOR else None
        if not isinstance(files, dict):
            files = None
    except (OSError, ValueError, KeyError, TypeError, AttributeError, RecursionError):
        files = None
    if files is None:
        raise SpecError("out_dir", f"{shown!r} is not empty and has no stt-codegen manifest: "
                                   "refusing to overwrite files it did not generate")
    unsafe = [name for name in files if not _flat_name(name) or name == MANIFEST]
    if unsafe:
        raise SpecError("out_dir", f"the manifest in {shown!r} lists {str(unsafe[0])[:80]!r}, "
                                   "not a file name stt-codegen writes: refusing to touch it")
    products = build_products(files)
    found = [name for name in entries if name in products and name not in files and (
        _is_our_cmake_build(out_dir / name, out_dir) if products[name] == "dir"
        else (out_dir / name).is_file() and not (out_dir / name).is_symlink())]
    foreign = [name for name in entries if name not in found and (
        name not in files and name != MANIFEST
        or not (out_dir / name).is_file() or (out_dir / name).is_symlink())]
    if foreign:
        raise SpecError("out_dir", f"{shown!r} holds {foreign[0]!r}, not a file listed in its "
                                   "stt-codegen manifest: refusing to overwrite or mix")
    if check_hashes:
        edited = [name for name in entries if name not in found and name != MANIFEST
                  and _file_sha256(out_dir / name) != files[name]]
        if edited:
            raise SpecError("out_dir", f"{shown!r} holds {edited[0]!r}, changed since "
                                       "stt-codegen generated it: refusing to overwrite it "
                                       "(move it away to regenerate)")
    return found


@contextlib.contextmanager
def _locked(parent: Path, name: str, shown: str, timeout: float) -> Iterator[None]:
    """Hold the flock of ``parent/.name.stt-codegen-lock``; remove the file when done."""
    path = parent / f".{name}{_LOCK}"
    deadline = time.monotonic() + timeout
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            raise SpecError("out_dir", f"cannot create the lock file {str(path)!r} beside "
                                       f"{shown!r}: {exc.strerror}") from None
        try:
            while True:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    break
                except BlockingIOError:
                    if time.monotonic() >= deadline:
                        holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
                        raise SpecError("out_dir", f"{shown!r} is being written by another "
                                        f"stt-codegen process (pid {holder or '?'}): gave up "
                                        f"after {timeout:g} s") from None
                    time.sleep(0.02)
            held = os.fstat(fd)
            try:
                now = os.stat(path, follow_symlinks=False)
            except FileNotFoundError:
                now = None
            if now is not None and (now.st_dev, now.st_ino) == (held.st_dev, held.st_ino):
                os.ftruncate(fd, 0)
                os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
                break
        except BaseException:
            os.close(fd)
            raise
        os.close(fd)        # its holder removed the file we locked: lock the new one
    try:
        yield
    finally:
        path.unlink(missing_ok=True)    # before unlocking: a waiter then sees it removed
        os.close(fd)


def _siblings(parent: Path, name: str, mark: str) -> list[Path]:
    pattern = re.compile(re.escape(f".{name}{mark}") + "[0-9a-f]{8}")
    return sorted(p for p in parent.iterdir() if pattern.fullmatch(p.name))


def _recover(parent: Path, target: Path) -> None:
    """Undo what a killed writer left (the caller holds the lock)."""
    olds = [p for p in _siblings(parent, target.name, _OLD) if p.is_dir() and not p.is_symlink()]
    if olds and not os.path.lexists(target):
        newest = max(olds, key=lambda p: p.stat().st_ctime_ns)
        os.rename(newest, target)
    for stale in _siblings(parent, target.name, _TMP) + _siblings(parent, target.name, _OLD):
        if stale.is_dir() and not stale.is_symlink():
            shutil.rmtree(stale, ignore_errors=True)
        elif os.path.lexists(stale):
            stale.unlink()


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _exchange(a: Path, b: Path) -> bool:
    """Swap two existing paths atomically (``renameat2(RENAME_EXCHANGE)``); ``False`` where
    the system has no such call (then nothing was done)."""
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _switch(new: Path, target: Path, exists: bool) -> None:
    """Put ``new`` at ``target``; afterwards ``new`` holds the old generation (if any)."""
    if not exists:
        os.rename(new, target)
    elif not _exchange(new, target):
        old = target.parent / f".{target.name}{_OLD}{secrets.token_hex(4)}"
        os.rename(target, old)
        try:
            os.rename(new, target)
        except BaseException:           # an error or Ctrl-C between the renames: undo
            if not os.path.lexists(target):
                os.rename(old, target)
            raise
        os.rename(old, new)


def write_generation(out_dir: str | Path, files: dict[str, bytes],
                     replace_edited: bool = False, lock_timeout: float | None = None) -> None:
    """Write ``files`` (name -> bytes, flat names) as the generation in ``out_dir``.

    See the module docstring: ``out_dir`` afterwards holds exactly ``files`` (and the
    build products carried over), or, on any error or kill, its previous content.

    Parameters
    ----------
    out_dir : str or path
        The folder (created if missing; its parent must exist and be writable).
    files : dict of str to bytes
        The generation, ``manifest.json`` included.
    replace_edited : bool
        Also replace listed files whose content changed since they were generated
        (``check --update`` on the version-controlled ``generated/``).
    lock_timeout : float, optional
        Seconds to wait for another writer of the same folder; default
        :data:`LOCK_TIMEOUT`.

    Raises
    ------
    SpecError
        Unsafe or unusable output folder, or another writer held it for ``lock_timeout``
        seconds (field ``out_dir``).
    """
    shown = str(out_dir)
    out_dir = Path(out_dir)
    for name in files:
        if not _flat_name(name):
            raise SpecError("out_dir", f"refusing to write file name {name!r}")
    if out_dir.is_symlink() and not out_dir.is_dir():
        raise SpecError("out_dir", f"{shown!r} is a symlink to no folder")
    if out_dir.exists() and not out_dir.is_dir():
        raise SpecError("out_dir", f"{shown!r} exists and is not a folder")
    parent = out_dir.parent if str(out_dir.parent) else Path(".")
    if not parent.is_dir():
        raise SpecError("out_dir", f"parent folder of {shown!r} does not exist")
    target = Path(os.path.realpath(out_dir))
    if target.parent == target:
        raise SpecError("out_dir", f"refusing to generate into the root folder {shown!r}")
    timeout = LOCK_TIMEOUT if lock_timeout is None else lock_timeout
    with _locked(target.parent, target.name, shown, timeout):
        new = None
        try:
            _recover(target.parent, target)
            exists = os.path.lexists(target)
            if exists and (target.is_symlink() or not target.is_dir()):
                raise SpecError("out_dir", f"{shown!r} exists and is not a folder")
            products = _inspect(target, shown, not replace_edited) if exists else []
            new = target.parent / f".{target.name}{_TMP}{secrets.token_hex(4)}"
            os.mkdir(new, 0o777)
            for name, data in files.items():
                write_durably(new / name, data)
            carried = build_products(files)
            for name in products:
                if name in carried and name not in files:
                    os.rename(target / name, new / name)
            if exists:
                os.chmod(new, target.stat().st_mode & 0o7777)
            fsync_path(new)
            _switch(new, target, exists)
            fsync_path(target.parent)
        except OSError as exc:
            raise SpecError("out_dir", f"cannot write {shown!r}: {exc.strerror or exc}") from None
        finally:
            if new is not None and os.path.lexists(new):
                shutil.rmtree(new, ignore_errors=True)
