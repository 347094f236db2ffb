"""One home per topic: no paragraph of the docs written twice, every page on the README's
map, and history in CHANGELOG.md only (code, templates, tests and docs say what and why,
never which issue asked for it)."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
#: A reference to a tracker entry: the word issue (or issues), a space, a number.
ISSUE = re.compile(r"\bissues?\s+#?\d", re.I)
#: Shortest paragraph that counts as written twice, in characters (whitespace collapsed).
LONG_PARAGRAPH = 200
#: Two pages sharing this many sentences of at least LONG_SENTENCE characters repeat a topic.
SHARED_SENTENCES = 2
LONG_SENTENCE = 40
#: Words that narrate history, which belongs in CHANGELOG.md ("is used to" is not history).
HISTORY = re.compile(r"\b(?:former(?:ly)?|before this change|no longer|previously|"
                     r"(?<!\bis )(?<!\bare )(?<!\bbe )(?<!\bbeen )used to)\b", re.I)


def pages(root: Path) -> list[Path]:
    return sorted((root / "docs").glob("*.md"))


def text_files(root: Path) -> list[Path]:
    """The files whose comments and prose must not cite issues: the package (code, templates,
    bundled specs), the tests and their specs, the docs and the README (not CHANGELOG.md)."""
    found = [root / "README.md", *pages(root)]
    for folder in ("stt_codegen", "templates", "tests"):
        found += [p for p in sorted((root / folder).rglob("*")) if p.is_file()
                  and p.suffix in {".py", ".toml", ".j2", ".c", ".h", ".md", ".txt", ".cmake"}]
    return found


def issue_citations(root: Path) -> list[str]:
    return [f"{path.relative_to(root)}:{n}: {line.strip()}"
            for path in text_files(root)
            for n, line in enumerate(path.read_text().splitlines(), 1) if ISSUE.search(line)]


def paragraphs(markdown: str) -> list[str]:
    """Blank-line separated blocks, whitespace collapsed (code blocks included)."""
    return [" ".join(block.split()) for block in re.split(r"\n[ \t]*\n", markdown)]


def long_sentences(markdown: str) -> set[str]:
    """The sentences of at least LONG_SENTENCE characters, whitespace collapsed."""
    text = " ".join(markdown.split())
    return {s for s in re.split(r"(?<=[.!?])\s+", text) if len(s) >= LONG_SENTENCE}


def repeated(root: Path) -> list[str]:
    """Paragraphs of at least LONG_PARAGRAPH characters that two pages of docs/ share, and
    pairs of pages sharing SHARED_SENTENCES long sentences or more."""
    texts = {p.name: p.read_text() for p in pages(root)}
    long = {name: {p for p in paragraphs(t) if len(p) >= LONG_PARAGRAPH}
            for name, t in texts.items()}
    sentences = {name: long_sentences(t) for name, t in texts.items()}
    found = []
    for a, b in itertools.combinations(sorted(texts), 2):
        found += [f"{a} and {b}: paragraph {p[:80]!r}" for p in sorted(long[a] & long[b])]
        common = sorted(sentences[a] & sentences[b])
        if len(common) >= SHARED_SENTENCES:
            found.append(f"{a} and {b}: {len(common)} sentences, {common[0][:80]!r}...")
    return found


def history(root: Path) -> list[str]:
    """The phrases of :data:`HISTORY` in the prose of docs/ (outside code blocks and code
    spans, which may quote a message), with the page and the text around them."""
    found = []
    for path in pages(root):
        text = re.sub(r"^```.*?^```[ \t]*$", "", path.read_text(), flags=re.S | re.M)
        text = " ".join(re.sub(r"`[^`]*`", "code", text).split())
        found += [f"{path.name}: ...{text[max(m.start() - 40, 0):m.end() + 20]}..."
                  for m in HISTORY.finditer(text)]
    return found


def readme_map(root: Path) -> list[str]:
    """The link targets of the README's "Documentation" section, in order."""
    readme = (root / "README.md").read_text()
    section = readme.split("## Documentation", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"^- \[[^\]]*\]\(([^)#]+)\)", section, flags=re.M)


def test_no_issue_numbers_outside_the_changelog():
    assert issue_citations(REPO) == []


def test_no_paragraph_is_written_twice_in_docs():
    assert repeated(REPO) == []


def test_no_history_in_docs():
    """The docs say what is, and why; what changed and when is CHANGELOG.md's."""
    assert history(REPO) == []


def test_the_history_check_sees_what_it_forbids(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "a.md").write_text(
        "# A\n\nThe bound is used to derive k. The check `no longer fits` is quoted.\n\n"
        "The step formerly took\nno longer than 2 us; Newton used to stop.\n\n"
        "```\npreviously, in a block\n```\n")
    found = history(tmp_path)
    assert len(found) == 3
    assert all(word in f for word, f in zip(["formerly", "no longer", "used to"], found))


def test_every_page_is_on_the_readmes_map_once():
    """The README's "Documentation" list names every page of docs/ (and CHANGELOG.md) once,
    with the topic it owns, and nothing else."""
    listed = readme_map(REPO)
    expected = [f"docs/{p.name}" for p in pages(REPO)] + ["CHANGELOG.md"]
    assert sorted(listed) == sorted(expected)
    assert len(set(listed)) == len(listed)


def test_the_checks_see_what_they_forbid(tmp_path):
    """An issue number in a comment, a paragraph copied between two pages and a page missing
    from the map are each reported; a sentence two pages share is not."""
    (tmp_path / "docs").mkdir()
    for folder in ("stt_codegen", "templates", "tests"):
        (tmp_path / folder).mkdir()
    comment = "# the cascade law (" + "Issue" + " 22)"
    (tmp_path / "stt_codegen" / "m.py").write_text(f"x = 1  {comment}\n")
    (tmp_path / "templates" / "t.c.j2").write_text("/* what and why */\n")
    shared = ("The certificate checks the tube against the union of the boxes, which contains "
              "the shape, so the margin it reports is a lower bound of the distance to the "
              "real shape. Simulation judges collisions against the shapes as given.")
    three = ("The design gives all boxes of one shape the same side. The plots draw the shapes "
             "and their boxes. A shape that meets the start is refused as such.")
    (tmp_path / "docs" / "a.md").write_text(f"# A\n\nSee also.\n\n{shared}\n\n{three}\n")
    (tmp_path / "docs" / "b.md").write_text(f"# B\n\nSee also.\n\n{shared}\n\nIn other "
                                            "words, the covering is conservative.\n")
    (tmp_path / "docs" / "c.md").write_text(f"# C\n\nSee also. Short. Words.\n\nIn other "
                                            f"words, the covering is conservative. {three}\n")
    (tmp_path / "README.md").write_text("# R\n\n## Documentation\n\n- [a](docs/a.md): A.\n")
    assert issue_citations(tmp_path) == [f"stt_codegen/m.py:1: x = 1  {comment}"]
    found = repeated(tmp_path)
    assert [f.split(":")[0] for f in found] == ["a.md and b.md"] * 2 + ["a.md and c.md"]
    assert "paragraph 'The certificate" in found[0]
    assert "2 sentences, 'Simulation judges" in found[1] and "3 sentences, 'A shape" in found[2]
    assert readme_map(tmp_path) == ["docs/a.md"]
