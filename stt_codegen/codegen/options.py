"""Options of ``stt-codegen generate``: target languages and floating-point precision."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..errors import SpecError

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
    """

    langs: tuple[str, ...] = LANGUAGES
    precision: str = "double"

    def to_json(self) -> dict:
        return {"langs": list(self.langs), "precision": self.precision}


def parse_options(langs: str | Sequence[str] = "c,python", precision: str = "double") -> Options:
    """Validate the languages (comma-separated, or a sequence such as a list, a tuple or a
    numpy array of strings) and the precision.

    Parameters
    ----------
    langs : str or sequence of str
        Languages among :data:`LANGUAGES` (``"c"``, ``"python"``).
    precision : str
        One of :data:`PRECISIONS` (``"double"``, ``"single"``).

    Returns
    -------
    Options
        The languages in :data:`LANGUAGES` order, without repeats, and the precision.

    Raises
    ------
    SpecError
        Unknown or empty language list (field ``languages``; ``--lang`` on the command
        line), unknown precision (field ``precision``).
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
    return Options(tuple(s for s in LANGUAGES if s in items), precision)
