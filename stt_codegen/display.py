"""Readable result objects: a title and labelled rows, as text (``summary()``, the command
line) and as Markdown (a notebook's ``_repr_markdown_``), written once for the design, the
run and the verification report."""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["Rows", "markdown", "shorten", "text"]

#: A summary's rows: (label, value in words), in order.
Rows = Sequence[tuple[str, str]]

#: Longest line of a summary, characters (a value is cut to fit, with "...").
WIDTH = 110


def shorten(value: str, width: int = WIDTH) -> str:
    """``value`` on one line of at most ``width`` characters (cut with ``"..."``).

    Parameters
    ----------
    value : str
        Any text; newlines become spaces.
    width : int
        Longest result, characters.

    Returns
    -------
    str
    """
    flat = " ".join(value.split())
    return flat if len(flat) <= width else flat[:width - 3].rstrip() + "..."


def text(title: str, rows: Rows) -> str:
    """The summary as text: the title, then ``"  label: value"`` a row (the values
    aligned; an empty label continues the row above), each line cut to :data:`WIDTH`.

    Parameters
    ----------
    title : str
        The first line.
    rows : sequence of (str, str)
        Label and value.

    Returns
    -------
    str
        ``1 + len(rows)`` lines.
    """
    width = max((len(label) for label, _ in rows), default=0)
    return "\n".join([shorten(title)] + [
        f"  {label + ':' if label else '':<{width + 1}} {shorten(value, WIDTH - width - 4)}"
        for label, value in rows])


def markdown(title: str, rows: Rows) -> str:
    """The summary as Markdown: the title in bold, the rows as a two-column table.

    Parameters
    ----------
    title : str
        The heading line.
    rows : sequence of (str, str)
        Label and value (``|`` escaped).

    Returns
    -------
    str
    """
    def cell(value: str) -> str:
        return " ".join(value.split()).replace("|", "\\|")
    lines = [f"**{cell(title)}**", ""]
    if rows:
        lines += ["| | |", "|---|---|"] + [f"| {cell(label)} | {cell(value)} |"
                                         for label, value in rows]
    return "\n".join(lines)
