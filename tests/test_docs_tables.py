"""Tables of the docs that the code decides, so that they cannot drift from it.

The status codes' table in docs/embedded.md is written from :class:`stt_codegen.tube.parameters.Status`
(its docstring's ``Attributes`` section) between two markers; ``python tests/test_docs_tables.py``
rewrites it after a change of the enum. The glossary of docs/architecture.md is written by
hand, and every code name in it must exist in the code. docs/cli.md names every command and
option of ``stt-codegen``, and nothing else.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import inspect
import itertools
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
    """The codes are listed on docs/embedded.md only: no other page writes one with its
    number (``STATUS_OK = 0``, ``OUTSIDE_TUBE (1``)."""
    names = "|".join(s.name for s in Status)
    listing = re.compile(rf"\b(?:\w*STATUS_)?(?:{names})`?\s+(?:=\s*|\()\d")
    found = [f"{p.name}: {m.group(0)}" for p in sorted((REPO / "docs").glob("*.md"))
             if p != EMBEDDED for m in listing.finditer(p.read_text())]
    assert found == []


def glossary_rows(markdown: str) -> list[list[str]]:
    """The cells of the glossary's rows (docs/architecture.md's section "Glossary"), the
    header and its rule left out."""
    section = markdown.split("## Glossary", 1)[1].split("\n## ", 1)[0]
    rows = [line.strip().strip("|").split("|") for line in section.splitlines()
            if line.startswith("| ")]
    return [[cell.strip() for cell in row] for row in rows[1:]]


def _has(owner, name: str) -> bool:
    """Whether ``name`` is an attribute, a dataclass field or a pydantic field of ``owner``."""
    fields = getattr(owner, "model_fields", None) or {}
    return (hasattr(owner, name) or name in fields
            or (dataclasses.is_dataclass(owner)
                and name in {f.name for f in dataclasses.fields(owner)}))


def code_name_exists(dotted: str) -> bool:
    """Whether ``stt_codegen.<dotted>`` is a module, or a name or field inside one."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            owner = importlib.import_module(".".join(["stt_codegen", *parts[:cut]]))
        except ModuleNotFoundError:
            continue
        for name in parts[cut:]:
            if not _has(owner, name):
                return False
            fields = getattr(owner, "model_fields", None) or {}
            owner = getattr(owner, name, None) if name not in fields else fields[name]
        return True
    return False


def _tables(annotation) -> list:
    """The pydantic models an annotation holds (``list[Union[...]]``, ``Annotated``...)."""
    import typing

    if isinstance(annotation, type) and hasattr(annotation, "model_fields"):
        return [annotation]
    return [m for arg in typing.get_args(annotation) for m in _tables(arg)]


def spec_key_exists(key: str) -> bool:
    """Whether a spec key written ``name``, ``[table] name`` or ``[[table]] name`` is a field
    of :class:`stt_codegen.spec.schema.SpecDocument` (any model of a list of tables)."""
    from stt_codegen.spec.schema import SpecDocument

    match = re.fullmatch(r"(?:\[\[?(\w+)\]\]? )?(\w+)", key)
    if not match:
        return False
    table, name = match.groups()
    if table is None:
        return name in SpecDocument.model_fields
    if table not in SpecDocument.model_fields:
        return False
    return any(name in m.model_fields for m in _tables(SpecDocument.model_fields[table].annotation))


def test_every_name_in_the_glossary_exists():
    """Each code name of docs/architecture.md's glossary is in the package, and each spec
    key in the spec's schema."""
    rows = glossary_rows(ARCHITECTURE.read_text())
    assert len(rows) >= 20 and all(len(row) == 4 for row in rows)
    code = [name for row in rows for name in re.findall(r"`([^`]+)`", row[2])]
    keys = [name for row in rows for name in re.findall(r"`([^`]+)`", row[3])]
    assert [name for name in code if not code_name_exists(name)] == []
    assert [key for key in keys if not spec_key_exists(key)] == []


def test_the_glossary_check_sees_missing_names():
    assert code_name_exists("tube.parameters.TubeDesign.prescribed_time")
    assert code_name_exists("spec.schema.TubeTable.smoothness")
    assert not code_name_exists("tube.parameters.TubeDesign.t_c")
    assert not code_name_exists("tube.nowhere.name")
    assert spec_key_exists("[[obstacles]] active") and spec_key_exists("[tube] smoothness")
    assert not spec_key_exists("[tube] nu") and not spec_key_exists("t_c")


#: The path of a command whose arguments another distribution adds, when it is not
#: installed (its parser takes the rest of the line): what cli.md writes under it is not
#: checked.
NOT_INSTALLED = "(not installed)"


def command_names() -> list[str]:
    """Every subcommand ``stt-codegen --help`` lists (those of other distributions too)."""
    from stt_codegen.cli import build_parser

    top = build_parser()
    return [name for action in top._actions if isinstance(action, argparse._SubParsersAction)
            for name in action.choices]


def command_options(parser: argparse.ArgumentParser | None = None,
                    path: str = "") -> dict[str, list[tuple[str, ...]]]:
    """``{command path: the option strings of each of its options}`` of ``stt-codegen``
    (``"design"``, ``"bench arenas"``, ``"import pointmaze"``; ``-h`` left out). A command
    whose parser takes the rest of the line (not installed) has the one option
    :data:`NOT_INSTALLED`."""
    from stt_codegen.cli import build_parser

    if parser is None:
        found: dict[str, list[tuple[str, ...]]] = {}
        for name in command_names():
            found.update(command_options(build_parser([name]).get_default("command_parser"), name))
        return found
    if any(a.nargs == argparse.REMAINDER for a in parser._actions):
        return {path: [(NOT_INSTALLED,)]}
    found = {path: [tuple(a.option_strings) for a in parser._actions
                    if a.option_strings and a.dest != "help"]}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found.update(command_options(sub, f"{path} {name}"))
    return found


def documented_commands(markdown: str) -> dict[str, set[str]]:
    """``{command path: the options written}`` of the code spans that start with
    ``stt-codegen`` (outside fenced blocks); the path is the lower-case words before the
    first argument or option."""
    text = re.sub(r"^```.*?^```[ \t]*$", "", markdown, flags=re.S | re.M)
    found: dict[str, set[str]] = {}
    for span in re.findall(r"`stt-codegen ([^`]*)`", text):
        words = span.split()
        path = " ".join(itertools.takewhile(lambda w: re.fullmatch(r"[a-z][a-z-]*", w), words))
        options = set(re.findall(r"(?<![\w-])(--?[a-z][\w-]*)", span))
        found.setdefault(path, set()).update(options)
    return found


def undocumented(markdown: str) -> list[str]:
    """The commands and options of ``stt-codegen`` that ``markdown`` does not write in a
    ``stt-codegen ...`` code span, and the options it writes that do not exist."""
    written = documented_commands(markdown)
    commands = command_options()
    opaque = [path for path, options in commands.items() if options == [(NOT_INSTALLED,)]]
    problems = [f"{path}: no such command" for path in written if path and path not in commands
                and not any(path.startswith(o + " ") for o in opaque)]
    for path, options in commands.items():
        if not any(w == path or w.startswith(path + " ") for w in written):
            problems.append(f"{path}: not documented")
            continue
        if path in opaque:
            continue
        known = {flag for strings in options for flag in strings} | {"--help", "--version"}
        problems += [f"{path} {strings[-1]}: not documented" for strings in options
                     if not set(strings) & written.get(path, set())]
        problems += [f"{path} {flag}: no such option"
                     for flag in sorted(written.get(path, set()) - known)]
    return problems


def test_cli_md_names_every_command_and_option():
    """Every subcommand (``bench`` and ``import`` ones included) and each of its options is
    written in docs/cli.md, in a ``stt-codegen ...`` code span, and no other."""
    assert undocumented((REPO / "docs" / "cli.md").read_text()) == []


def test_the_cli_check_sees_what_it_forbids():
    """A command left out, an option left out and an option that does not exist are each
    reported."""
    text = (REPO / "docs" / "cli.md").read_text()
    text = text.replace("`stt-codegen schema`", "`stt-codegen schema --pretty`")
    text = text.replace(" [--no-host]", "").replace("`stt-codegen cases`", "cases")
    problems = undocumented(text)
    assert "cases: not documented" in problems
    assert "embedded --no-host: not documented" in problems
    assert "schema --pretty: no such option" in problems


if __name__ == "__main__":
    rewrite()
    sys.exit(0)
