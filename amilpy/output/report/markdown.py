"""The report in Markdown (GitHub-flavoured: pipe tables, fenced code), with the
figures as PNGs beside it."""

from __future__ import annotations

import os
import re
from typing import TextIO
from urllib.parse import quote

from .. import tables as T
from ..words import visible
from .document import Code, Document, Figure, Heading, TableBlock, Text

# What Markdown would read as markup: emphasis, code, table cells, links, HTML tags.
# An underscore inside a word (MC_MAX) and a lone < or > ("W1 < 0") are plain text.
_SPECIAL = re.compile(r"[\\*`|\[\]]|(?<![A-Za-z0-9])_|_(?![A-Za-z0-9])|<(?=[A-Za-z/!])")


def escape(text: str) -> str:
    """Text as Markdown shows it: no markup, no HTML tag, no control character."""
    return _SPECIAL.sub(lambda m: "\\" + m.group(0), visible(text))


def fence(lines: list[str]) -> str:
    """A code fence longer than any run of backticks in `lines` (CommonMark), so no
    line of a listing can close it and let what follows be read as Markdown/HTML."""
    longest = max((len(run) for line in lines for run in re.findall("`+", line)), default=0)
    return "`" * max(3, longest + 1)


def table(t: T.Table, out: TextIO) -> None:
    if t.caption:
        out.write(f"**{escape(t.caption)}**\n\n")
    out.write("| " + " | ".join(escape(c.name) for c in t.columns) + " |\n|")
    out.write("".join("---|" if c.left else "---:|" for c in t.columns) + "\n")
    for row in t.rows():
        out.write("| " + " | ".join(escape(v) for v in row) + " |\n")
    for note in t.notes:
        out.write(f"\n{escape(note)}\n")
    out.write("\n")


def render(doc: Document, out_dir: str, out: TextIO) -> None:
    figure = 0
    for b in doc.blocks:
        if isinstance(b, Heading):
            out.write(f"{'#' * b.level} {escape(b.text)}\n\n")
        elif isinstance(b, Text):
            out.write(f"**{escape(b.text)}**\n\n" if b.strong else f"{escape(b.text)}\n\n")
        elif isinstance(b, Code):
            lines = [visible(line) for line in b.numbered()]
            mark = fence(lines)
            out.write(mark + ("amil" if b.kind == "listing" else "") + "\n"
                      + "".join(line + "\n" for line in lines) + mark + "\n\n")
        elif isinstance(b, TableBlock):
            table(b.table, out)
        elif isinstance(b, Figure):
            figure += 1
            rel = quote(os.path.relpath(b.path, out_dir).replace(os.sep, "/"))
            name = f"{doc.words['figure']} {figure}"
            out.write(f"![{name}]({rel})\n\n*{name}: {escape(b.caption)}*\n\n")
        else:  # pragma: no cover - every block kind is rendered above
            raise TypeError(type(b).__name__)
