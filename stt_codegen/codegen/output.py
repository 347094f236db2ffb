"""Writing a generation into ``-o DIR``: only inside DIR, only over our own files, atomically.

Rules (:func:`write_generation`):

* ``DIR``'s parent must exist; ``DIR`` is created if missing.
* If ``DIR`` exists it must be empty or hold a ``manifest.json`` of ours; every entry of
  ``DIR`` must be a regular file (not a symlink) that manifest lists (or the manifest
  itself), with the SHA-256 the manifest records (a file edited since it was generated
  is not ours any more). Anything else (a foreign file, a folder, a symlink, a
  manifest of another tool, a manifest naming a path rather than a flat file name) is
  refused with a :class:`SpecError` and nothing is written.
* Only entries of ``DIR`` itself are ever replaced or removed: a name from a manifest is
  used only if it is a flat file name and an entry of ``DIR``.
* Every file is first written to a temporary folder inside ``DIR``, then moved into
  place with ``os.replace`` (the manifest last); files of the previous generation that
  are no longer generated are removed. On any error the temporary folder is removed and,
  if ``DIR`` was created by this call, ``DIR`` too.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path

from ..errors import SpecError
from .generate import GENERATOR, MANIFEST

_TMP_PREFIX = ".stt-codegen-tmp-"


def _flat_name(name) -> bool:
    return (isinstance(name, str) and bool(name) and "/" not in name and "\\" not in name
            and "\0" not in name and name not in (".", "..") and not name.startswith("."))


def _file_sha256(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def previous_files(out_dir: Path, check_hashes: bool = True) -> list[str]:
    """Names of the previous generation's files in ``out_dir`` (else ``[]``).

    Parameters
    ----------
    check_hashes : bool
        Refuse files whose content differs from the SHA-256 the manifest records.

    Raises
    ------
    SpecError
        ``out_dir`` holds entries that are not ours (field ``out_dir``).
    """
    entries = sorted(p.name for p in out_dir.iterdir())
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
        raise SpecError("out_dir", f"{str(out_dir)!r} is not empty and has no stt-codegen manifest: "
                              "refusing to overwrite files it did not generate")
    unsafe = [name for name in files if not _flat_name(name) or name == MANIFEST]
    if unsafe:
        raise SpecError("out_dir", f"the manifest in {str(out_dir)!r} lists {str(unsafe[0])[:80]!r}, "
                              "not a file name stt-codegen writes: refusing to touch it")
    foreign = [name for name in entries if name not in files and name != MANIFEST
               or not (out_dir / name).is_file() or (out_dir / name).is_symlink()]
    if foreign:
        raise SpecError("out_dir", f"{str(out_dir)!r} holds {foreign[0]!r}, not a file listed in its "
                              "stt-codegen manifest: refusing to overwrite or mix")
    if check_hashes:
        edited = [name for name in entries if name != MANIFEST
                  and _file_sha256(out_dir / name) != files[name]]
        if edited:
            raise SpecError("out_dir", f"{str(out_dir)!r} holds {edited[0]!r}, changed since "
                                  "stt-codegen generated it: refusing to overwrite it "
                                  "(move it away to regenerate)")
    return [name for name in entries if name != MANIFEST]


def write_generation(out_dir: str | Path, files: dict[str, bytes],
                     replace_edited: bool = False) -> None:
    """Write ``files`` (name -> bytes, flat names) into ``out_dir``; see the module docstring.

    ``replace_edited`` also replaces listed files whose content changed since they were
    generated (``check --update`` on the version-controlled ``generated/``).

    Raises
    ------
    SpecError
        Unsafe or unusable output folder (field ``out_dir``).
    """
    out_dir = Path(out_dir)
    for name in files:
        if not _flat_name(name):
            raise SpecError("out_dir", f"refusing to write file name {name!r}")
    if out_dir.exists() and not out_dir.is_dir():
        raise SpecError("out_dir", f"{str(out_dir)!r} exists and is not a folder")
    parent = out_dir.parent if str(out_dir.parent) else Path(".")
    if not parent.is_dir():
        raise SpecError("out_dir", f"parent folder of {str(out_dir)!r} does not exist")
    created = not out_dir.exists()
    if created:
        try:
            out_dir.mkdir()
        except OSError as exc:
            raise SpecError("out_dir", f"cannot create {str(out_dir)!r}: {exc.strerror}") from None
        old: list[str] = []
    else:
        old = previous_files(out_dir, check_hashes=not replace_edited)
    tmp = None
    try:
        tmp = Path(tempfile.mkdtemp(prefix=_TMP_PREFIX, dir=out_dir))
        for name, data in files.items():
            with open(tmp / name, "wb") as fh:
                fh.write(data)
        for name in sorted(files, key=lambda n: n == MANIFEST):
            os.replace(tmp / name, out_dir / name)
        for name in old:
            if name not in files:
                (out_dir / name).unlink(missing_ok=True)
    except OSError as exc:
        if created:
            shutil.rmtree(out_dir, ignore_errors=True)
        raise SpecError("out_dir", f"cannot write into {str(out_dir)!r}: {exc.strerror or exc}") from None
    except BaseException:
        if created:
            shutil.rmtree(out_dir, ignore_errors=True)
        raise
    finally:
        if tmp is not None and tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
