"""Tables of the docs that the code decides, so that they cannot drift from it.

The status codes' table in docs/embedded.md is written from :class:`stt_codegen.tube.parameters.Status`
(its docstring's ``Attributes`` section) between two markers; ``python tests/test_docs_tables.py``
rewrites it after a change of the enum. The glossary of docs/architecture.md is written by
hand, and every code name in it must exist in the code.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import re
import sys
from pathlib import Path

from stt_codegen.tube.parameters import Status

REPO = Path(__file__).resolve().parent.parent
EMBEDDED = REPO / "docs" / "embedded.md"
ARCHITECTURE = REPO / "docs" / "architecture.md"
BEGIN = "<!-- status codes: written by tests/test_docs_tables.py from tube.parameters.Status -->"
END = "<!-- end of the status codes -->"


def status_meanings(enum=Status) -> dict[str, str]:
    """``{member name: its description}`` from the enum docstring's ``Attributes`` section,
    whitespace collapsed, reStructuredText's double backquotes made markdown's single ones."""
    doc = inspect.cleandoc(enum.__doc__)
    section = doc.split("Attributes\n----------\n", 1)[1]
    entries = re.findall(r"^(\w+) : \S+\n((?:    .*\n?)+)", section, flags=re.M)
    return {name: " ".join(text.replace("``", "`").split()) for name, text in entries}


def status_table(enum=Status) -> str:
    """The markdown table of the status codes, by code: the C macro (``P`` the spec's C
    name), the Python name and the meaning."""
    meanings = status_meanings(enum)
    rows = ["| code | C (`P.h`) | Python | meaning |", "|---|---|---|---|"]
    rows += [f"| {int(s)} | `P_STATUS_{s.name}` | `STATUS_{s.name}` | {meanings[s.name]} |"
             for s in sorted(enum, key=int)]
    return "\n".join(rows)


def marked_block(text: str) -> str:
    """The text between :data:`BEGIN` and :data:`END`, without the blank lines around it."""
    return text.split(BEGIN + "\n", 1)[1].split(END, 1)[0].strip("\n")


def rewrite(path: Path = EMBEDDED) -> None:
    """Put :func:`status_table` between the markers of ``path``."""
    text = path.read_text()
    head, rest = text.split(BEGIN + "\n", 1)
    path.write_text(f"{head}{BEGIN}\n\n{status_table()}\n\n{END}{rest.split(END, 1)[1]}")


def test_the_status_table_is_the_enums():
    """docs/embedded.md's table lists every member of Status, by code, with its docstring's
    meaning (``python tests/test_docs_tables.py`` rewrites it)."""
    assert marked_block(EMBEDDED.read_text()) == status_table()


def test_the_status_table_sees_every_member():
    """A member without a description would be a KeyError, and one more member one more row."""
    import enum

    class Two(enum.IntEnum):
        """Two codes.

        Attributes
        ----------
        FIRST : 0
            The first,
            on two lines.
        SECOND : 1
            The second.
        """

        SECOND = 1
        FIRST = 0

    assert status_table(Two).splitlines()[2:] == [
        "| 0 | `P_STATUS_FIRST` | `STATUS_FIRST` | The first, on two lines. |",
        "| 1 | `P_STATUS_SECOND` | `STATUS_SECOND` | The second. |"]
    assert set(status_meanings()) == {s.name for s in Status}


def test_other_pages_link_to_the_status_codes():
    """The codes are listed on docs/embedded.md only: no other page spells two of them with
    their numbers."""
    listing = re.compile(r"STATUS_\w+`?\s+(?:=\s*|\()?\d")
    found = [f"{p.name}: {m.group(0)}" for p in sorted((REPO / "docs").glob("*.md"))
             if p != EMBEDDED for m in listing.finditer(p.read_text())]
    assert found == []


if __name__ == "__main__":
    rewrite()
    sys.exit(0)
