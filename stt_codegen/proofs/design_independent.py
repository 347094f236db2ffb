"""The design-independent proofs of ``verify``, proved once and kept in an on-disk cache.

Most of the work of ``stt-codegen verify`` is SymPy proving facts about the deployed
expressions that no spec parameter enters: the equality of each deployed piece with the
paper's formula (``deployed.*``), Lemma 3.3's limits and smooth max, the error transform of
Theorem 4.1, and the symbolic parts of the rate bounds and of the adaptive law's checks
(:func:`~stt_codegen.proofs.lemma.reach_rate_form`,
:func:`~stt_codegen.proofs.lemma.bump_rate_form`,
:func:`~stt_codegen.proofs.adaptive.adaptive_law_form`). :func:`design_independent_proofs`
proves them and stores the outcome in ``$XDG_CACHE_HOME/stt-codegen`` (default
``~/.cache/stt-codegen``), one JSON file per key, written atomically.

The key (:func:`proof_key`) is a SHA-256 over everything the proofs depend on:

* the serialization of every CasADi piece they print
  (:func:`~stt_codegen.proofs.deployed.proved_pieces`) and the source of the printer
  (every module of :mod:`stt_codegen.codegen.emit`), so a changed piece or printer misses
  the cache (the printed SymPy expressions are a function of these two);
* the source of the modules that state and run the proofs (:mod:`.deployed`,
  :mod:`.statements`, :mod:`.lemma`, :mod:`.transform`, :mod:`.adaptive`, :mod:`.check`
  and this one), so a changed proof misses the cache;
* the constants the domains use (``E_MAX``, ``GAMMA_D_MIN``, the exponent clamp), the
  versions of Python, SymPy, mpmath, NumPy and CasADi, the proof parameters and
  :data:`CACHE_FORMAT`.

An entry that cannot be read, does not parse, has another key or format, or has the
wrong shape is ignored and proved again (then overwritten). A cache directory that cannot
be written costs time only. No spec-dependent number is ever read from the cache.
"""

from __future__ import annotations

import hashlib
import json
import os
import secrets
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import casadi
import mpmath
import numpy as np
import sympy as sp

from ..codegen import emit
from ..tube import pieces
from ..tube.parameters import E_MAX, GAMMA_D_MIN
from . import check as _check
from . import adaptive, deployed, lemma, statements, transform
from .check import Check

__all__ = ["CACHE_FORMAT", "Proofs", "design_independent_proofs", "load_cached", "proof_key",
           "prove", "store"]

#: Version of the cache file's layout; files of another version are never read.
CACHE_FORMAT = 1

#: Highest derivative order of the explicit one-sided limits of Lemma 3.3.
LEMMA_ORDERS = 3

#: Modules whose source is part of the key: they state and run the proofs.
_PROOF_MODULES = (deployed, statements, lemma, transform, adaptive, _check,
                  sys.modules[__name__])

#: The forms of :attr:`Proofs.forms`: name -> type, or for a dict its keys' types.
_FORMS = {"reach_rate": bool, "bump_rate": bool,
          "adaptive_law": {"trigger": str, "trigger_positive": bool,
                           "upper_bound_proved": bool, "df_da": str}}

#: Called with a short label before each group of proofs.
Progress = Callable[[str], None]

#: Proofs already obtained in this process, by key (a second ``verify`` reads no file).
_IN_PROCESS: dict[str, "Proofs"] = {}


@dataclass(frozen=True)
class Proofs:
    """Outcome of the design-independent proofs.

    Attributes
    ----------
    checks : tuple of Check
        ``deployed.*`` (:func:`~stt_codegen.proofs.deployed.deployed_checks`), Lemma 3.3
        (:func:`~stt_codegen.proofs.lemma.lemma_checks`) and Theorem 4.1
        (:func:`~stt_codegen.proofs.transform.error_transform_checks`), in that order.
    forms : dict
        The symbolic parts of the design-dependent checks: ``reach_rate``
        (:func:`~stt_codegen.proofs.lemma.reach_rate_form`), ``bump_rate``
        (:func:`~stt_codegen.proofs.lemma.bump_rate_form`) and ``adaptive_law``
        (:func:`~stt_codegen.proofs.adaptive.adaptive_law_form`).
    from_cache : bool
        Read from the cache (not compared).
    """

    checks: tuple[Check, ...]
    forms: dict
    from_cache: bool = field(default=False, compare=False)

    def to_json(self) -> dict:
        """The cache file's payload (without key and format)."""
        return {"checks": [{"name": c.name, "passed": c.passed, "detail": c.detail,
                            "data": c.data} for c in self.checks],
                "forms": self.forms}


def cache_directory() -> Path:
    """``$XDG_CACHE_HOME/stt-codegen``, or ``~/.cache/stt-codegen`` when it is unset."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "stt-codegen"


def proof_key(max_n: int = 3) -> str:
    """SHA-256 hex digest of everything the proofs depend on (see the module docstring).

    Parameters
    ----------
    max_n : int
        Largest dimension of the error transform proved.

    Returns
    -------
    str
        64 hexadecimal characters.
    """
    digest = hashlib.sha256()

    def part(label: str, text: str | bytes) -> None:
        data = text.encode() if isinstance(text, str) else text
        digest.update(f"{label}:{len(data)}:".encode())
        digest.update(data)

    part("setup", json.dumps({
        "format": CACHE_FORMAT, "python": list(sys.version_info[:2]),
        "sympy": sp.__version__, "mpmath": mpmath.__version__, "numpy": np.__version__,
        "casadi": casadi.__version__,
        "max_n": max_n, "orders": LEMMA_ORDERS,
        "constants": [repr(E_MAX), repr(GAMMA_D_MIN), repr(pieces.EXP_ARGUMENT_BOUND)]},
        sort_keys=True))
    for module in _PROOF_MODULES:
        part(module.__name__, Path(module.__file__).read_bytes())
    for source in sorted(Path(emit.__file__).parent.glob("*.py")):
        part(f"emit/{source.name}", source.read_bytes())
    for name, function in sorted(deployed.proved_pieces(max_n).items()):
        part(name, function.serialize())
    return digest.hexdigest()


def prove(max_n: int = 3, progress: Progress | None = None) -> Proofs:
    """Run the design-independent proofs in SymPy (no cache).

    Parameters
    ----------
    max_n : int
        Largest dimension of the error transform proved.
    progress : callable, optional
        Called with a label before each group of proofs.

    Returns
    -------
    Proofs
        The proofs, freshly computed.
    """
    say = progress or (lambda label: None)
    say("deployed pieces")
    checks = list(deployed.deployed_checks())
    say("lemma 3.3")
    checks += lemma.lemma_checks(orders=LEMMA_ORDERS)
    say("error transform")
    checks += transform.error_transform_checks(max_n=max_n)
    say("rate bound forms")
    forms = {"reach_rate": lemma.reach_rate_form(), "bump_rate": lemma.bump_rate_form(),
             "adaptive_law": adaptive.adaptive_law_form()}
    return Proofs(tuple(checks), forms)


def _has_shape(value: object, shape: object) -> bool:
    if isinstance(shape, dict):
        return (isinstance(value, dict) and set(value) == set(shape)
                and all(_has_shape(value[k], t) for k, t in shape.items()))
    return isinstance(value, shape)


def _parse(payload: object, key: str) -> Proofs | None:
    """The proofs of a cache file's payload, ``None`` when it is not a valid entry."""
    if not isinstance(payload, dict) or payload.get("format") != CACHE_FORMAT \
            or payload.get("key") != key:
        return None
    rows, forms = payload.get("checks"), payload.get("forms")
    if not isinstance(rows, list) or not rows or not _has_shape(forms, _FORMS):
        return None
    checks = []
    for row in rows:
        if not (isinstance(row, dict) and isinstance(row.get("name"), str)
                and isinstance(row.get("passed"), bool) and isinstance(row.get("detail"), str)
                and isinstance(row.get("data"), dict)):
            return None
        checks.append(Check(row["name"], row["passed"], row["detail"], row["data"]))
    return Proofs(tuple(checks), forms, from_cache=True)


def _cache_file(key: str) -> Path:
    return cache_directory() / f"proofs-{key}.json"


def load_cached(key: str) -> Proofs | None:
    """The cached proofs of ``key``, or ``None`` (no entry, unreadable, corrupt, stale).

    Parameters
    ----------
    key : str
        The proofs' key (:func:`proof_key`).

    Returns
    -------
    Proofs or None
        The cached proofs.
    """
    try:
        payload = json.loads(_cache_file(key).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return _parse(payload, key)


def store(key: str, proofs: Proofs) -> bool:
    """Write ``proofs`` under ``key`` atomically (a temporary file, then ``os.replace``).

    Parameters
    ----------
    key : str
        The proofs' key (:func:`proof_key`).
    proofs : Proofs
        The proofs to cache.

    Returns
    -------
    bool
        ``False`` when the cache directory cannot be written (nothing is left behind).
    """
    path = _cache_file(key)
    text = json.dumps({"format": CACHE_FORMAT, "key": key, **proofs.to_json()}, indent=1)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        try:
            tmp.unlink(missing_ok=True)
        except OSError:     # the folder itself could not be made
            pass
        return False
    return True


def design_independent_proofs(max_n: int = 3, cache: bool = True,
                              progress: Progress | None = None) -> Proofs:
    """The design-independent proofs, from the cache when it holds them for this key.

    Parameters
    ----------
    max_n : int
        Largest dimension of the error transform proved (``verify`` uses
        ``min(n, 3)``).
    cache : bool
        Use the cache: this process's earlier result for the same key, else the on-disk
        entry (:func:`cache_directory`), written when missing. ``False`` proves
        everything again and touches no file.
    progress : callable, optional
        Called with a label before each group of proofs (``"cached proofs"`` on a hit).

    Returns
    -------
    Proofs
        ``from_cache`` tells which way they were obtained; the checks, their evidence and
        the forms are the same either way.

    Examples
    --------
    >>> from stt_codegen.proofs.design_independent import design_independent_proofs
    >>> proofs = design_independent_proofs(max_n=2)      # doctest: +SKIP
    >>> all(c.passed for c in proofs.checks)             # doctest: +SKIP
    True
    """
    try:
        key = proof_key(max_n) if cache else None
    except OSError:         # a proof module's source is not readable: no key, no cache
        key = None
    if key is None:
        return prove(max_n, progress)
    found = _IN_PROCESS.get(key) or load_cached(key)
    if found is not None:
        if progress:
            progress("cached proofs")
    else:
        found = prove(max_n, progress)
        store(key, found)
    _IN_PROCESS[key] = found
    return found
