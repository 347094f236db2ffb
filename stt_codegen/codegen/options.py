"""Options of ``stt-codegen generate``: target languages, floating-point precision, and
whether the C takes its tube as data."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..errors import SpecError
from .tube_data import DEFAULT_CAPACITY, TubeCapacity

__all__ = ["LANGUAGES", "Options", "PRECISIONS", "parse_options"]

#: Supported languages, in the canonical order used in file lists and manifests.
LANGUAGES = ("c", "python")
#: Supported precisions of the C code (the Python module always uses Python floats).
PRECISIONS = ("double", "single")


@dataclass(frozen=True)
class Options:
    """What to generate.

    Attributes
    ----------
    langs : tuple of str
        Subset of :data:`LANGUAGES`, canonical order, non-empty.
    precision : str
        One of :data:`PRECISIONS`; applies to the C code (and the vectors' tolerances).
    tube_data : TubeCapacity or None
        The generated code (C and Python) takes its tube as data, up to these sizes
        (:mod:`.tube_data`); ``None`` (default): the design's tube in tables.
    """

    langs: tuple[str, ...] = LANGUAGES
    precision: str = "double"
    tube_data: TubeCapacity | None = None

    def to_json(self) -> dict:
        out = {"langs": list(self.langs), "precision": self.precision}
        if self.tube_data is not None:
            out["tube_data"] = self.tube_data.to_json()
        return out


def parse_options(langs: str | Sequence[str] = "c,python", precision: str = "double",
                  tube_data: bool | TubeCapacity | None = None) -> Options:
    """Validate the languages (comma-separated, or a sequence such as a list, a tuple or a
    numpy array of strings), the precision and the tube as data.

    Parameters
    ----------
    langs : str or sequence of str
        Languages among :data:`LANGUAGES` (``"c"``, ``"python"``).
    precision : str
        One of :data:`PRECISIONS` (``"double"``, ``"single"``).
    tube_data : bool or TubeCapacity, optional
        The generated code takes its tube as data (``True``:
        :data:`~.tube_data.DEFAULT_CAPACITY`), in C and in Python.

    Returns
    -------
    Options
        The languages in :data:`LANGUAGES` order, without repeats, the precision and the
        tube's capacity (``None``: tables).

    Raises
    ------
    SpecError
        Unknown or empty language list (field ``languages``; ``--lang`` on the command
        line), unknown precision (field ``precision``), a ``tube_data`` that is neither
        ``True`` nor a :class:`~.tube_data.TubeCapacity` (field ``tube_data``).
    """
    items = [s.strip() for s in langs.split(",")] if isinstance(langs, str) else list(langs)
    if not items or any(not s for s in items):
        raise SpecError("languages", f"expected a comma-separated list of {', '.join(LANGUAGES)}")
    unknown = [s for s in items if s not in LANGUAGES]
    if unknown:
        raise SpecError("languages", f"unknown language {unknown[0]!r} (known: {', '.join(LANGUAGES)})")
    if precision not in PRECISIONS:
        raise SpecError("precision", f"unknown precision {precision!r} "
                                       f"(known: {', '.join(PRECISIONS)})")
    capacity = DEFAULT_CAPACITY if tube_data is True else (tube_data or None)
    if capacity is not None and not isinstance(capacity, TubeCapacity):
        raise SpecError("tube_data", f"expected True or a TubeCapacity, got {tube_data!r}")
    return Options(tuple(s for s in LANGUAGES if s in items), precision, capacity)
