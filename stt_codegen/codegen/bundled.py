"""The committed output ``generated/``: one folder per bundled case and precision.

Layout: ``generated/<case>/double/`` holds C and Python (``--lang c,python --precision
double``); ``generated/<case>/single/`` holds C only (``--lang c --precision single``):
the Python module computes with Python floats whatever the precision, so it is kept once.
:func:`drift` regenerates every folder into memory and compares it byte for byte with
the committed files.

CasADi version policy: the package supports ``casadi>=3.6.7,<3.9`` (pyproject.toml), but
CasADi's instruction stream differs between versions (3.8 adds ``OP_TWICE`` and numbers
its work registers differently, on the same SX graph), so the printed bodies do too. The
committed ``generated/`` is the output of :data:`REFERENCE_CASADI_VERSION`, the one place
naming it; under another supported version generation works and the generated code passes
the same vectors, but it is not byte-identical to ``generated/``, and ``stt-codegen check``
says so.
"""

from __future__ import annotations

import difflib
from pathlib import Path

from ..design.search import design_tube
from ..spec.loader import bundled_cases, load_spec
from .api import design_files
from .options import Options
from .output import write_generation

__all__ = ["LAYOUT", "drift", "update_generated", "version_note"]

#: The CasADi version whose output ``generated/`` holds (the byte-identical reference).
REFERENCE_CASADI_VERSION = "3.8.2"

#: Sub-folder name -> options of the committed generations.
LAYOUT = {"double": Options(("c", "python"), "double"), "single": Options(("c",), "single")}


def expected_tree() -> dict[str, bytes]:
    """Every committed file, keyed by its path relative to ``generated/`` (POSIX)."""
    tree: dict[str, bytes] = {}
    for case in bundled_cases():
        design = design_tube(load_spec(case))
        for sub, options in LAYOUT.items():
            files = design_files(design, options)
            for name, data in files.items():
                tree[f"{case}/{sub}/{name}"] = data
    return tree


def actual_tree(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` (hidden ones too), keyed by relative POSIX path."""
    if not root.is_dir():
        return {}
    return {p.relative_to(root).as_posix(): p.read_bytes()
            for p in sorted(root.rglob("*")) if p.is_file()}


def version_note() -> str:
    """One line naming the CasADi version compared against, and whether it is the reference.

    Returns
    -------
    str
        The note ``stt-codegen check`` prints with its verdict.
    """
    import casadi
    installed = casadi.__version__
    if installed == REFERENCE_CASADI_VERSION:
        return f"compared against a fresh generation with CasADi {installed} (the reference version)"
    return (f"compared against a fresh generation with CasADi {installed}; generated/ refers to "
            f"CasADi {REFERENCE_CASADI_VERSION}: differences in the printed bodies are expected "
            f"under another version (install casadi=={REFERENCE_CASADI_VERSION} to check)")


def drift(root: Path, expected: dict[str, bytes] | None = None) -> list[str]:
    """Unified diffs (one string per differing file; empty: identical) of ``root``.

    Parameters
    ----------
    root : pathlib.Path
        The ``generated/`` folder to compare.
    expected : dict of str to bytes, optional
        The files expected, keyed by path relative to ``root`` (POSIX); default a fresh
        generation of every bundled case (:func:`expected_tree`).

    Returns
    -------
    list of str
        One unified diff per file that differs, or a line naming a missing or stray file,
        in path order.
    """
    expected = expected_tree() if expected is None else expected
    actual = actual_tree(root)
    out = []
    label = root.as_posix().rstrip("/")
    for path in sorted(set(expected) | set(actual)):
        old, new = actual.get(path), expected.get(path)
        if old == new:
            continue
        if old is None:
            out.append(f"missing: {label}/{path}\n")
        elif new is None:
            out.append(f"not generated (stray file): {label}/{path}\n")
        else:
            try:
                a = old.decode("utf-8").splitlines(keepends=True)
                b = new.decode("utf-8").splitlines(keepends=True)
            except UnicodeDecodeError:
                out.append(f"binary files differ: {label}/{path}\n")
                continue
            out.append("".join(difflib.unified_diff(
                a, b, fromfile=f"{label}/{path} (committed)",
                tofile=f"{label}/{path} (regenerated)")))
    return out


def update_generated(root: Path) -> None:
    """Regenerate every committed folder under ``root`` (each written atomically).

    Parameters
    ----------
    root : pathlib.Path
        The ``generated/`` folder; created if missing.
    """
    tree = expected_tree()
    folders: dict[str, dict[str, bytes]] = {}
    for path, data in tree.items():
        folder, name = path.rsplit("/", 1)
        folders.setdefault(folder, {})[name] = data
    root.mkdir(exist_ok=True)
    for folder, files in folders.items():
        (root / folder).parent.mkdir(parents=True, exist_ok=True)
        write_generation(root / folder, files, replace_edited=True)
