"""Jinja2 environment over the package ``stt_codegen.templates`` (the top-level ``templates/``).

Templates are located with :func:`importlib.resources.files`, so they are found both in
the editable install and in a wheel. Spec-derived strings reach templates only as
validated identifiers (:func:`c_identifier`) or through the comment filters
(``c_comment``, ``py_comment``), which drop anything but printable ASCII and break
comment terminators.
"""

from __future__ import annotations

import keyword
import re
from functools import lru_cache
from importlib.resources import files

import jinja2

from ..errors import SpecError

__all__ = ["c_identifier", "c_real", "render"]

_C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto "
    "if inline int long register restrict return short signed sizeof static struct switch "
    "typedef union unsigned void volatile while _Bool _Complex _Imaginary".split())


def c_identifier(name: str, field: str = "name") -> str:
    """``name`` if it is a C and Python identifier that is not a keyword and has no
    leading underscore, else :class:`SpecError` (``field``).

    Parameters
    ----------
    name : str
        The candidate identifier (a spec's name or a prefix).
    field : str
        The field an error names.

    Returns
    -------
    str
        ``name`` itself.

    Raises
    ------
    SpecError
        ``name`` is not ``[A-Za-z][A-Za-z0-9_]{0,63}`` or is a C or Python keyword.
    """
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,63}", name):
        raise SpecError(field, f"{name!r} is not usable as a C identifier")
    if name in _C_KEYWORDS or keyword.iskeyword(name):
        raise SpecError(field, f"{name!r} is a C or Python keyword")
    return name


def _printable(text: str) -> str:
    return "".join(ch if " " <= ch <= "~" else "?" for ch in str(text))


def c_comment(text: str) -> str:
    """Text safe inside a C block comment (printable ASCII, no ``*/`` or ``/*``)."""
    return _printable(text).replace("*/", "* /").replace("/*", "/ *")


def py_comment(text: str) -> str:
    """Text safe inside a Python ``#`` comment or docstring (printable ASCII, no quotes
    or backslashes)."""
    return _printable(text).replace("\\", "/").replace('"', "'")


def c_real(value: float, single: bool) -> str:
    """A C literal reading back exactly to ``value`` (double) or to its nearest float.

    Parameters
    ----------
    value : float
        A finite number.
    single : bool
        Print a ``float`` literal (``f`` suffix), else a ``double`` one.

    Returns
    -------
    str
        The shortest decimal that reads back to ``value`` (``repr``), with ``.0`` added to
        an integer.

    Raises
    ------
    ValueError
        ``value`` is infinite or NaN.
    """
    text = repr(float(value))
    if "e" not in text and "." not in text and "inf" not in text and "nan" not in text:
        text += ".0"
    if text in ("inf", "-inf", "nan"):
        raise ValueError(f"non-finite constant {value!r} in generated C")
    return text + ("f" if single else "")


@lru_cache(maxsize=1)
def environment() -> jinja2.Environment:
    """The Jinja2 environment (strict undefined, no autoescape, trailing newline kept)."""
    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(_load),
        undefined=jinja2.StrictUndefined,
        autoescape=False,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters["c_comment"] = c_comment
    env.filters["py_comment"] = py_comment
    return env


def _load(name: str) -> str:
    return files("stt_codegen.templates").joinpath(name).read_text(encoding="utf-8")


def render(template: str, **context) -> str:
    """Render template ``template`` (a file name in ``templates/``) with ``context``.

    Parameters
    ----------
    template : str
        The template's file name, e.g. ``"c_source.c.j2"``.
    **context
        The template's variables.

    Returns
    -------
    str
        The rendered text.
    """
    return environment().get_template(template).render(**context)
