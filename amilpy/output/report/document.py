"""The report as a list of blocks (headings, text, code, tables, figures), built
once from the model and its runs; each format renders the same blocks.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from ...parse.unparse import expr_text
from ...result import Run
from .. import tables as T
from .. import words as W
from ..printout import method_text, printer_plots


@dataclass(frozen=True)
class Heading:
    text: str
    level: int  # 1 the title, 2 a section, 3 a part of a section


@dataclass(frozen=True)
class Text:
    text: str
    strong: bool = False  # a warning a reader must not miss (partial results)


# Code on a page is this many characters wide, line number included: what the LaTeX
# body's \small typewriter and the PDF's 7.5-point DejaVu Sans Mono fit in 17 cm.
# A longer line goes on in the next row, which the continuation mark begins.
CODE_CHARS = 100
CONTINUED = "\u21aa"  # (a hooked arrow: "this row goes on from the one above")


@dataclass(frozen=True)
class Row:
    """A row of code as set on a page: the gutter (a line number, blank, or the
    continuation mark) and a piece of a line starting at `start` in it."""

    gutter: str
    text: str
    line: int  # index of the line it comes from
    start: int  # where in that line the piece starts


@dataclass(frozen=True)
class Code:
    lines: list[str]
    kind: str  # "listing" (numbered; highlighted in LaTeX), "equations", "plot"

    def numbered(self) -> list[str]:
        """The lines as shown: the listing with its line numbers."""
        if self.kind != "listing":
            return self.lines
        width = len(str(len(self.lines)))
        return [f"{i:>{width}}  {line}" for i, line in enumerate(self.lines, start=1)]

    def rows(self, chars: int = CODE_CHARS) -> list[Row]:
        """The lines set `chars` wide: the listing numbered, a longer line broken
        (after a space or a comma near the edge, where there is one) and its rows
        after the first marked as continued. A printer plot is not broken (its
        renderers set it smaller instead)."""
        digits = len(str(len(self.lines))) if self.kind == "listing" else 0
        gutter = digits + 2 if self.kind == "listing" else 2
        width = max(chars - gutter, 20)
        mark = " " * (gutter - 2) + CONTINUED + " "
        out = []
        for i, line in enumerate(self.lines):
            first = f"{i + 1:>{digits}}  " if self.kind == "listing" else ""
            if self.kind == "plot":
                out.append(Row(first, line, i, 0))
                continue
            start = 0
            for piece in _pieces(line, width if self.kind == "listing" else chars):
                out.append(Row(first if start == 0 else mark, piece, i, start))
                start += len(piece)
        return out


def _pieces(line: str, width: int) -> list[str]:
    """`line` cut into pieces of at most `width` characters (the later ones two
    narrower: the mark is wider than a character), after a space or a comma in the
    last third of a piece where there is one. The pieces joined are the line."""
    out = []
    rest = line.rstrip()
    limit = width
    while len(rest) > limit:
        low = limit * 2 // 3
        cut = max(rest.rfind(" ", low, limit), rest.rfind(",", low, limit)) + 1
        cut = cut if cut > 0 else limit
        out.append(rest[:cut])
        rest = rest[cut:]
        limit = width - 2
    out.append(rest)
    return out


@dataclass(frozen=True)
class TableBlock:
    table: T.Table


@dataclass(frozen=True)
class Figure:
    path: str  # the PNG (Markdown)
    caption: str
    vector: str | None = None  # the same figure as PDF (LaTeX), when written
    # draws the figure again into a matplotlib Figure or SubFigure (`into=`: the PDF
    # report sets it on its page as vector graphics); None: only the files are there
    redraw: Callable[..., object] | None = field(default=None, compare=False)
    size: tuple[float, float] = (8.0, 4.8)  # inches, as drawn


Block = Heading | Text | Code | TableBlock | Figure


@dataclass
class Document:
    title: str
    lang: str
    words: dict[str, str]
    blocks: list[Block] = field(default_factory=list)
    partial: bool = False

    def add(self, *blocks: Block | None) -> None:
        self.blocks.extend(b for b in blocks if b is not None)


def equation_lines(model) -> list[tuple[str, str]]:
    """(section, equation) in evaluation order: INITIAL, then DYNAMIC's algebraic
    equations as sorted, then the state derivatives."""
    out = [("INITIAL", f"{e.target} = {expr_text(model, e.expr)}") for e in model.initial]
    out += [("DYNAMIC", f"{e.target} = {expr_text(model, e.expr)}") for e in model.dynamic]
    for s in model.states:
        out.append(("DYNAMIC", f"d{s.name}/dt = {expr_text(model, s.deriv)}    "
                               f"({s.name}(0) = {expr_text(model, s.ic)})"))
    return out


def data_rows(model, run: Run, words: dict[str, str]) -> list[tuple[str, float, str, str, str]]:
    """(name, value, unit, description, where defined) for every data and INITIAL
    value; unit and description from the `!` comment on the defining line."""
    notes = W.name_notes(model)
    rows = []
    for name in model.data_names:
        span = model.spans.get(name)
        where = f"{model.data_kinds.get(name, 'PARAM')}, {words['line']} {span.line}" \
            if span else ""
        rows.append((name, run.constants.get(name, math.nan), *notes.get(name, ("", "")),
                     where))
    for e in model.initial:
        rows.append((e.target, run.constants.get(e.target, math.nan),
                     *notes.get(e.target, ("", "")), f"INITIAL, {words['line']} {e.span.line}"))
    return rows


def build(model, runs: Sequence[Run], figures: Sequence[Figure], path: str,
          lang: str, checks: Sequence | None = None) -> Document:
    """The report of `model` (an api.Model) and its runs with its `figures`;
    `checks` each run's accuracy check, if made."""
    words = W.WORDS[lang]
    ir = model.ir
    titles = runs[0].titles if runs and runs[0].titles else [os.path.basename(path)]
    doc = Document(titles[0], lang, words, partial=any(not r.ok for r in runs))
    doc.add(Heading(titles[0], 1), *(Text(t) for t in titles[1:]))
    if doc.partial:
        doc.add(Text(words["partial report"], strong=True))
    doc.add(Text(f"{words['model file']}: {os.path.basename(path)}"))
    doc.add(Heading(words["listing"], 2), Code(ir.source.splitlines(), "listing"))
    doc.add(Heading(words["data"], 2),
            TableBlock(T.data_table(data_rows(ir, runs[0], words), words)))
    doc.add(Heading(words["equations"], 2),
            Code([f"{s:8} {t}" for s, t in equation_lines(ir)], "equations"))
    labels = W.run_labels(runs)
    for k, (run, label) in enumerate(zip(runs, labels, strict=True), start=1):
        doc.add(Heading(W.run_heading(run, k, label, words), 2),
                Text(method_text(run)),
                TableBlock(T.printout_table(run)))
        for plot in printer_plots(run):
            doc.add(Code(plot.strip("\n").splitlines(), "plot"))
        head = ("RANGE", words["minimum"], words["time"], words["maximum"], words["time"])
        for table in (T.range_table(run, head), T.events_table(run, words),
                      T.terminal_table(run, words)):
            if table is not None:
                doc.add(TableBlock(table))
        if run.observed:
            doc.add(Text(f"{words['data vs run']} ({os.path.basename(run.observed[0].source)})",
                         strong=True))
            for table in (T.observed_table(run, (words["time"], words["variable"],
                                                 words["observed"], words["simulated"],
                                                 words["residual"])),
                          T.residual_table(run, (words["variable"], words["count"],
                                                 words["rms"], words["largest"]))):
                doc.add(TableBlock(table))
        doc.add(*(Text(w) for w in run.warnings))
        if checks is not None and k <= len(checks):
            check = checks[k - 1]
            doc.add(Text(words["accuracy"] + (f" ({check.how})" if check.how else ""),
                         strong=True),
                    *(Text(line) for line in W.accuracy_lines(check, words)))
        if not run.ok:
            doc.add(Text(f"{words['partial']}: {run.message}", strong=True))
    if figures:
        doc.add(Heading(words["plots"], 2), *figures)
    return doc
