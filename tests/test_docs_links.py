"""The documentation's relative links resolve, and the README stays a front page."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

import stt_codegen

REPO = Path(__file__).resolve().parent.parent
DOCUMENTS = [REPO / "README.md", REPO / "CHANGELOG.md", *sorted((REPO / "docs").glob("*.md"))]
LINK = re.compile(r"\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)\)")


def prose(markdown: str) -> str:
    """The text outside fenced code blocks (a ``# comment`` in a block is not a heading)."""
    return re.sub(r"^```.*?^```[ \t]*$", "", markdown, flags=re.S | re.M)


def slug(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading.strip()).lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every heading's anchor in a markdown file, with GitHub's -1, -2 for repeats."""
    found: set[str] = set()
    counts: dict[str, int] = {}
    for heading in re.findall(r"^#{1,6}[ \t]+(.+?)[ \t#]*$", prose(path.read_text()), re.M):
        base = slug(heading)
        n = counts.get(base, 0)
        found.add(base if n == 0 else f"{base}-{n}")
        counts[base] = n + 1
    return found


def relative_links(path: Path) -> list[str]:
    """The link targets of a markdown file that point inside the repository (not those in
    code: a code span becomes a word first, so ``[`x`](y)`` stays a link)."""
    text = re.sub(r"`[^`\n]*`", "code", prose(path.read_text()))
    return [t for t in LINK.findall(text) if not re.match(r"[a-z][a-z0-9+.-]*:", t)]


def broken_links(path: Path) -> list[str]:
    broken = []
    for target in relative_links(path):
        file_part, _, anchor = target.partition("#")
        linked = (path.parent / file_part).resolve() if file_part else path
        if not linked.exists():
            broken.append(f"{target}: no such file")
        elif anchor and (linked.suffix != ".md" or anchor not in anchors(linked)):
            broken.append(f"{target}: no heading with anchor #{anchor}")
    return broken


@pytest.mark.parametrize("path", DOCUMENTS, ids=lambda p: p.relative_to(REPO).as_posix())
def test_relative_links_resolve(path):
    assert broken_links(path) == []


def test_the_check_sees_broken_links(tmp_path):
    """A missing file and a missing heading are both reported; a good link is not."""
    (tmp_path / "a.md").write_text("# Title\n\n## The `x` part, (1)\n\n```sh\n# not a heading\n```\n")
    page = tmp_path / "b.md"
    page.write_text("[ok](a.md#the-x-part-1) [`ok`](a.md) [gone](c.md) [no](a.md#not-a-heading)\n"
                    "[web](https://example.org/x.md) `[code](in.md)`\n```\n[in](block.md)\n```\n")
    assert broken_links(page) == ["c.md: no such file",
                                  "a.md#not-a-heading: no heading with anchor #not-a-heading"]


def test_the_readme_is_a_front_page():
    """At most 150 lines of at most 100 characters; the two commands in its first 30 lines,
    in a ```sh block; its test command is the one .ci/run runs, a member a line."""
    lines = (REPO / "README.md").read_text().splitlines()
    assert len(lines) <= 150
    assert [n for n, line in enumerate(lines, 1) if len(line) > 100] == []
    head = "\n".join(lines[:30])
    block = re.search(r"^```sh\n(.*?)^```$", head, flags=re.S | re.M)
    assert block, "no ```sh block in the README's first 30 lines"
    commands = [c for c in block.group(1).splitlines() if c and not c.startswith("#")]
    assert commands[0] == "python3 -m pip install . && stt-codegen demo"
    test_command = commands[1]
    assert test_command.startswith('python3 -m pip install -e ".[test]"')
    # .ci/run runs each member of the `&&` list on a line of its own, in order (a failing
    # member that is not the last of an `&&` list does not stop a `set -e` script).
    ci = (REPO / ".ci" / "run").read_text().splitlines()
    members = test_command.split(" && ")
    where = [ci.index(member) for member in members]
    assert where == sorted(where)


def test_the_documented_spec_file_loads():
    """docs/spec-format.md's commented file is a valid spec, every optional key included."""
    text = (REPO / "docs" / "spec-format.md").read_text()
    blocks = re.findall(r"^```toml\n(.*?)^```$", text, flags=re.S | re.M)
    assert len(blocks) == 1
    spec = stt_codegen.Spec.from_dict(tomllib.loads(blocks[0]))
    assert spec.name == "omnirobot-s1" and spec.prescribed_time == 9.0
