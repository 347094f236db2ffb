"""Writing a generation into ``-o DIR``: only inside DIR, only over our own files, atomically.

Rules (:func:`write_generation`):

* ``DIR``'s parent must exist; ``DIR`` is created if missing.
* If ``DIR`` exists it must be empty or hold a ``manifest.json`` of ours; every entry of
  ``DIR`` must be a file that manifest lists (or the manifest itself). Anything else
  (a foreign file, a folder, a manifest of another tool) is refused with a
  :class:`SpecError` and nothing is written.
* Every file is first written to a temporary folder inside ``DIR``, then moved into
  place with ``os.replace`` (the manifest last); files of the previous generation that
  are no longer generated are removed. On any error the temporary folder is removed and,
  if ``DIR`` was created by this call, ``DIR`` too.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

from ..errors import SpecError
from .generate import GENERATOR, MANIFEST

_TMP_PREFIX = ".stt-codegen-tmp-"


def previous_files(out_dir: Path) -> list[str]:
    """Names listed by the manifest of a previous generation in ``out_dir`` (else ``[]``).

    Raises
    ------
    SpecError
        ``out_dir`` holds entries that are not ours (field ``-o``).
    """
    entries = sorted(p.name for p in out_dir.iterdir())
    if not entries:
        return []
    path = out_dir / MANIFEST
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        listed = sorted(data["files"]) if data.get("generator") == GENERATOR else None
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        listed = None
    if listed is None:
        raise SpecError("-o", f"{str(out_dir)!r} is not empty and has no stt-codegen manifest: "
                              "refusing to overwrite files it did not generate")
    allowed = set(listed) | {MANIFEST}
    foreign = [name for name in entries if name not in allowed
               or not (out_dir / name).is_file() or (out_dir / name).is_symlink()]
    if foreign:
        raise SpecError("-o", f"{str(out_dir)!r} holds {foreign[0]!r}, not listed in its "
                              "stt-codegen manifest: refusing to overwrite or mix")
    return listed


def write_generation(out_dir: str | Path, files: dict[str, bytes]) -> None:
    """Write ``files`` (name -> bytes, flat names) into ``out_dir``; see the module docstring.

    Raises
    ------
    SpecError
        Unsafe or unusable output folder (field ``-o``).
    """
    out_dir = Path(out_dir)
    for name in files:
        if not name or "/" in name or "\\" in name or name in (".", "..") or name.startswith("."):
            raise SpecError("-o", f"refusing to write file name {name!r}")
    if out_dir.exists() and not out_dir.is_dir():
        raise SpecError("-o", f"{str(out_dir)!r} exists and is not a folder")
    parent = out_dir.parent if str(out_dir.parent) else Path(".")
    if not parent.is_dir():
        raise SpecError("-o", f"parent folder of {str(out_dir)!r} does not exist")
    created = not out_dir.exists()
    if created:
        try:
            out_dir.mkdir()
        except OSError as exc:
            raise SpecError("-o", f"cannot create {str(out_dir)!r}: {exc.strerror}") from None
        old: list[str] = []
    else:
        old = previous_files(out_dir)
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
        raise SpecError("-o", f"cannot write into {str(out_dir)!r}: {exc.strerror or exc}") from None
    except BaseException:
        if created:
            shutil.rmtree(out_dir, ignore_errors=True)
        raise
    finally:
        if tmp is not None and tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
