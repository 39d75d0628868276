"""The report as a PDF drawn by matplotlib (no other dependency): A4 pages of
monospaced text, then one page per figure with its caption.

Nothing is cut: text longer than a line wraps with an indent; tables are split
by columns to fit the width (TIME starts each part) and, across pages, repeat
their header; a printer plot wider than a line is set in a smaller font.
"""

from __future__ import annotations

import io
import textwrap
from collections.abc import Iterator
from dataclasses import dataclass

from .. import tables as T
from ..files import atomic_write
from ..plot import literal_text
from ..words import visible
from .document import Code, Document, Figure, Heading, TableBlock, Text

PAGE = (8.27, 11.69)  # A4, inches
FONT = 6.6  # points
CHARS = 128  # characters of DejaVu Sans Mono at FONT across the text width
LINES = 88  # lines a page holds
LEFT, TOP = 0.06, 0.965
MIN_FONT = 3.5  # a wider printer plot shrinks down to this


@dataclass(frozen=True)
class Line:
    text: str
    style: str = "text"  # "title", "heading", "strong", "text", "head" (a table's header)
    head: str | None = None  # the header a table row repeats on a new page
    chars: int = CHARS  # the width this line is set to (wider for a printer plot)


def _wrap(text: str, indent: int = 4) -> list[str]:
    if len(text) <= CHARS:
        return [text]
    return textwrap.wrap(text, CHARS, subsequent_indent=" " * indent, break_long_words=True,
                         replace_whitespace=False, drop_whitespace=False) or [text]


def lines(doc: Document) -> Iterator[Line]:
    """The text pages' lines; figures have pages of their own (see `render`)."""
    for b in doc.blocks:
        if isinstance(b, Heading):
            yield Line("")
            for part in _wrap(b.text):
                yield Line(part, "title" if b.level == 1 else "heading")
            if b.level == 1:
                yield Line("=" * min(len(b.text), CHARS))
            yield Line("")
        elif isinstance(b, Text):
            for part in _wrap(b.text):
                yield Line(part, "strong" if b.strong else "text")
        elif isinstance(b, Code) and b.kind == "plot":
            width = max(CHARS, *(len(line) for line in b.lines))
            yield Line("")
            yield from (Line(line, chars=width) for line in b.lines)
        elif isinstance(b, Code):
            indent = len(str(len(b.lines))) + 2 if b.kind == "listing" else 9
            for line in b.numbered():
                yield from (Line(part) for part in _wrap(line, indent))
        elif isinstance(b, TableBlock):
            yield from _table(b.table)
        elif isinstance(b, Figure):
            continue
        else:  # pragma: no cover - every block kind is rendered above
            raise TypeError(type(b).__name__)


def _table(t: T.Table) -> Iterator[Line]:
    if t.caption:
        yield Line("")
        yield Line(t.caption, "strong")
    for head, rows in T.text_blocks(t, max_chars=CHARS, per_block=CHARS):
        yield Line("")
        yield Line(head, "head")
        for row in rows:
            yield from (Line(part, head=head) for part in _wrap(row, 14))
    for note in t.notes:
        yield Line(note)


def pages(doc: Document) -> list[list[Line]]:
    """The lines cut into pages; a table row that starts a page brings its header,
    and a heading never ends one."""
    out: list[list[Line]] = [[]]
    for line in lines(doc):
        page = out[-1]
        room = LINES - len(page)
        if room <= 0 or (line.style in ("heading", "title") and room < 4):
            page = []
            out.append(page)
            if line.head is not None:
                page.append(Line(line.head, "head"))
        if not page and not line.text:
            continue  # no blank line at the top of a page
        page.append(line)
    return [p for p in out if p]


@literal_text
def render(doc: Document, path: str) -> int:
    """Write the PDF; return its number of pages."""
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure as MplFigure
    from matplotlib.image import imread

    buf = io.BytesIO()
    count = 0
    step = FONT * 1.2 / 72 / PAGE[1]  # one line, as a fraction of the page's height
    with PdfPages(buf) as pdf:
        text_pages = pages(doc)
        for number, page in enumerate(text_pages, start=1):
            fig = MplFigure(figsize=PAGE)
            for i, line in enumerate(page):
                size = max(MIN_FONT, FONT * min(1.0, CHARS / line.chars))
                fig.text(LEFT, TOP - i * step, visible(line.text), family="DejaVu Sans Mono",
                         fontsize=size, va="top",
                         weight="bold" if line.style in ("title", "heading", "strong",
                                                         "head") else "normal")
            _footer(fig, doc, number)
            pdf.savefig(fig)
            count += 1
        figures = [b for b in doc.blocks if isinstance(b, Figure)]
        for k, block in enumerate(figures, start=1):
            fig = MplFigure(figsize=PAGE)
            ax = fig.add_axes((0.05, 0.35, 0.9, 0.6))
            ax.imshow(imread(block.path))
            ax.axis("off")
            caption = visible(f"{doc.words['figure']} {k}: {block.caption}")
            fig.text(0.08, 0.33, "\n".join(textwrap.wrap(caption, 110)), fontsize=9,
                     va="top")
            _footer(fig, doc, len(text_pages) + k)
            pdf.savefig(fig)
            count += 1
    atomic_write(path, buf.getvalue())
    return count


def _footer(fig, doc: Document, number: int) -> None:
    from ..words import shorten

    fig.text(0.5, 0.02, f"{shorten(doc.title, 80)} — {number}", ha="center", fontsize=6,
             color="0.4")
