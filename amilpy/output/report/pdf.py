"""The report as a PDF drawn by matplotlib (no other dependency), laid out as the
LaTeX one is: A4, 2 cm margins, proportional text for headings and prose, a
typewriter face for the listing, equations and tables, and the figures drawn
again on the page as vector graphics, the text's width, each with its caption
right below it.

Nothing leaves the text block: prose is wrapped by its measured width; a
listing or equation line longer than `CODE_CHARS` goes on in the next row,
marked; tables are split by columns to fit (TIME starts each part) and, across
pages, repeat their header; a printer plot wider than a line is set smaller.
A heading is never the last thing on a page, and a figure is never cut (one taller
than a page holds is drawn narrower).
"""

from __future__ import annotations

import io
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from .. import tables as T
from ..files import atomic_write
from ..plot import literal_text
from ..words import visible
from .document import CODE_CHARS, Code, Document, Figure, Heading, TableBlock, Text

PAGE = (8.27, 11.69)  # A4, inches
PT = 72.0  # points per inch
MARGIN = 0.79 * PT  # 2 cm, left, right and top
BOTTOM = 0.95 * PT  # room for the footer
WIDTH = PAGE[0] * PT - 2 * MARGIN  # the text block's width, points
HEIGHT = PAGE[1] * PT - MARGIN - BOTTOM
SANS, MONO = "DejaVu Sans", "DejaVu Sans Mono"
MONO_EM = 0.602  # DejaVu Sans Mono's advance, in em
SIZES = {"title": 14.0, "heading": 11.0, "subheading": 9.5, "text": 8.5, "caption": 8.0,
         "code": 7.5, "table": 7.0}
LEADING = 1.25  # line height, in font sizes
TABLE_CHARS = int(WIDTH / (MONO_EM * SIZES["table"]))  # a table row's characters
MIN_PLOT_FONT = 3.5  # a wide printer plot shrinks down to this


@dataclass
class Box:
    """Something set on a page: `height` points tall, drawn by `draw(fig, top)`
    with `top` in points from the page's top. `keep` more points must follow on
    the same page (a heading keeps with what it heads); `head` is drawn again
    first when a table row starts a page."""

    height: float
    draw: Callable[[object, float], None]
    keep: float = 0.0
    head: Box | None = None
    gap: float = 0.0  # space above, dropped at the top of a page
    whole: bool = False  # a figure: what keeps with it keeps with all of it


def _frac(x: float, y: float) -> tuple[float, float]:
    """Points from the page's top-left corner -> figure fractions."""
    return x / (PAGE[0] * PT), 1.0 - y / (PAGE[1] * PT)


def _text_box(text: str, style: str, family: str = SANS, bold: bool = False,
              size: float | None = None, gap: float = 0.0, x: float = 0.0,
              colour: str = "black") -> Box:
    size = size or SIZES[style]
    line = size * LEADING

    def draw(fig, top: float) -> None:
        fig.text(*_frac(MARGIN + x, top + size), visible(text), family=family, fontsize=size,
                 weight="bold" if bold else "normal", va="baseline", color=colour)
    return Box(line, draw, gap=gap)


class _Measure:
    """Widths of proportional text, in points, from matplotlib's own font metrics."""

    def __init__(self) -> None:
        from matplotlib.backends.backend_agg import RendererAgg
        from matplotlib.font_manager import FontProperties

        self.renderer = RendererAgg(10, 10, PT)
        self.props = {(size, bold): FontProperties(family=SANS, size=size,
                                                   weight="bold" if bold else "normal")
                      for size in set(SIZES.values()) for bold in (False, True)}
        self.cache: dict[tuple[str, float, bool], float] = {}

    def width(self, text: str, size: float, bold: bool = False) -> float:
        key = (text, size, bold)
        if key not in self.cache:
            self.cache[key] = self.renderer.get_text_width_height_descent(
                text, self.props[size, bold], ismath=False)[0]
        return self.cache[key]

    def wrap(self, text: str, size: float, bold: bool = False, width: float = WIDTH
             ) -> list[str]:
        """`text` in lines no wider than `width` (a word too long for a line is cut)."""
        lines: list[str] = []
        for paragraph in visible(text).split("\n"):
            current = ""
            for word in paragraph.split(" "):
                trial = f"{current} {word}" if current else word
                if self.width(trial, size, bold) <= width:
                    current = trial
                    continue
                if current:
                    lines.append(current)
                while self.width(word, size, bold) > width:  # (a long unbroken word)
                    cut = max(1, int(len(word) * width / self.width(word, size, bold)) - 1)
                    lines.append(word[:cut])
                    word = word[cut:]
                current = word
            lines.append(current)
        return lines


def boxes(doc: Document) -> Iterator[Box]:
    """The document as boxes, in reading order."""
    measure = _Measure()
    figures = 0
    for b in doc.blocks:
        if isinstance(b, Heading):
            style = {1: "title", 2: "heading"}.get(b.level, "subheading")
            size = SIZES[style]
            lines = measure.wrap(b.text, size, bold=True)
            for k, line in enumerate(lines):
                last = k == len(lines) - 1
                box = _text_box(line, style, bold=True, gap=size * 1.1 if k == 0 else 0.0)
                box.keep = 4 * SIZES["text"] * LEADING if last else 0.0
                if last:
                    box.height += size * 0.4
                yield box
        elif isinstance(b, Text):
            size = SIZES["text"]
            lines = measure.wrap(b.text, size, bold=b.strong)
            for k, line in enumerate(lines):
                yield _text_box(line, "text", bold=b.strong,
                                gap=size * 0.4 if k == 0 else 0.0)
        elif isinstance(b, Code) and b.kind == "plot":
            width = max((len(line) for line in b.lines), default=1)
            size = max(MIN_PLOT_FONT, min(SIZES["code"], WIDTH / (MONO_EM * width)))
            for k, line in enumerate(b.lines):
                yield _text_box(line, "code", MONO, size=size, gap=6.0 if k == 0 else 0.0)
        elif isinstance(b, Code):
            rows = b.rows(CODE_CHARS)
            colour = "0.45"
            for k, row in enumerate(rows):
                yield _code_row(row.gutter, row.text, colour, gap=4.0 if k == 0 else 0.0)
        elif isinstance(b, TableBlock):
            yield from _table(b.table, measure)
        elif isinstance(b, Figure):
            figures += 1
            yield _figure(b, figures, doc, measure)
        else:  # pragma: no cover - every block kind is rendered above
            raise TypeError(type(b).__name__)


def _code_row(gutter: str, text: str, colour: str, gap: float = 0.0) -> Box:
    size = SIZES["code"]
    advance = MONO_EM * size

    def draw(fig, top: float) -> None:
        y = _frac(0, top + size)[1]
        if gutter.strip():
            fig.text(_frac(MARGIN, 0)[0], y, gutter, family=MONO, fontsize=size,
                     va="baseline", color=colour)
        fig.text(_frac(MARGIN + advance * len(gutter), 0)[0], y, visible(text), family=MONO,
                 fontsize=size, va="baseline")
    return Box(size * LEADING, draw, gap=gap)


def _rule(top: float, fig, weight: float = 0.5) -> None:
    from matplotlib.lines import Line2D

    (x0, y), (x1, _) = _frac(MARGIN, top), _frac(MARGIN + WIDTH, top)
    fig.add_artist(Line2D([x0, x1], [y, y], transform=fig.transFigure, linewidth=weight,
                          color="0.3"))


def _table(t: T.Table, measure: _Measure) -> Iterator[Box]:
    size = SIZES["table"]
    row_height = size * LEADING
    if t.caption:
        for k, line in enumerate(measure.wrap(t.caption, SIZES["text"], bold=True)):
            box = _text_box(line, "text", bold=True, gap=6.0 if k == 0 else 0.0)
            box.keep = 4 * row_height
            yield box
    for head_text, rows in T.text_blocks(t, max_chars=TABLE_CHARS, per_block=TABLE_CHARS):
        def draw_head(fig, top: float, text=head_text) -> None:
            _rule(top + 1.0, fig, 0.8)
            fig.text(*_frac(MARGIN, top + size + 2.0), text, family=MONO, fontsize=size,
                     weight="bold", va="baseline")
            _rule(top + row_height + 3.0, fig)
        head = Box(row_height + 4.0, draw_head, keep=3 * row_height, gap=6.0)
        yield head
        for row in rows:
            box = _text_box(row, "table", MONO)
            box.head = Box(head.height, draw_head)
            yield box

        def draw_end(fig, top: float) -> None:
            _rule(top + 1.0, fig, 0.8)
        yield Box(3.0, draw_end)
    for note in t.notes:
        yield from (_text_box(line, "text") for line in measure.wrap(note, SIZES["text"]))


def _figure(b: Figure, number: int, doc: Document, measure: _Measure) -> Box:
    """The figure the text's width, drawn again on the page (vector) where it can
    be, else its PNG; the caption right below."""
    width_in, height_in = b.size
    caption = measure.wrap(f"{doc.words['figure']} {number}: {b.caption}",
                           SIZES["caption"], width=WIDTH * 0.9)
    line = SIZES["caption"] * LEADING
    # the text's width, unless that is taller than a page holds with its caption and a
    # heading above (a figure of many stacked axes): then narrower, centred
    tallest = HEIGHT - len(caption) * line - 10.0 - 3 * SIZES["heading"]
    image = min(WIDTH * height_in / width_in, tallest)
    width = image * width_in / height_in
    left = MARGIN + (WIDTH - width) / 2

    def draw(fig, top: float) -> None:
        x0, y_top = _frac(left, top)
        x1, y_bottom = _frac(left + width, top + image)
        if b.redraw is not None:
            grid = fig.add_gridspec(3, 3, width_ratios=[x0, x1 - x0, 1 - x1],
                                    height_ratios=[1 - y_top, y_top - y_bottom, y_bottom],
                                    wspace=0, hspace=0)
            b.redraw(into=fig.add_subfigure(grid[1, 1]))
        else:
            from matplotlib.image import imread

            ax = fig.add_axes((x0, y_bottom, x1 - x0, y_top - y_bottom))
            ax.imshow(imread(b.path))
            ax.axis("off")
        for k, text in enumerate(caption):
            fig.text(0.5, _frac(0, top + image + 6.0 + (k + 1) * line)[1], text, family=SANS,
                     fontsize=SIZES["caption"], ha="center", va="baseline")
    return Box(image + 10.0 + len(caption) * line, draw, gap=10.0, whole=True)


def pages(doc: Document) -> list[list[tuple[float, Box]]]:
    """The boxes placed: (top in points, box) per page."""
    out: list[list[tuple[float, Box]]] = [[]]
    y = 0.0
    items = list(boxes(doc))
    for i, box in enumerate(items):
        gap = box.gap if out[-1] else 0.0
        after = 0.0
        if box.keep and i + 1 < len(items):
            after = box.keep
            if items[i + 1].whole:  # (a heading over a figure goes with the figure)
                after = max(after, items[i + 1].height)
        if out[-1] and y + gap + box.height + after > HEIGHT:
            out.append([])
            y, gap = 0.0, 0.0
            if box.head is not None:
                out[-1].append((MARGIN, box.head))
                y += box.head.height
        out[-1].append((MARGIN + y + gap, box))
        y += gap + box.height
    return [p for p in out if p]


@literal_text
def render(doc: Document, path: str) -> int:
    """Write the PDF; return its number of pages."""
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure as MplFigure

    buf = io.BytesIO()
    laid = pages(doc)
    with PdfPages(buf, metadata={"Title": visible(doc.title), "CreationDate": None}) as pdf:
        for number, page in enumerate(laid, start=1):
            fig = MplFigure(figsize=PAGE)
            for top, box in page:
                box.draw(fig, top)
            _footer(fig, doc, number)
            pdf.savefig(fig)
    atomic_write(path, buf.getvalue())
    return len(laid)


def _footer(fig, doc: Document, number: int) -> None:
    from ..words import shorten

    fig.text(0.5, 0.035, f"{shorten(doc.title, 80)} — {number}", ha="center", fontsize=7,
             color="0.4", family=SANS)

