"""The report as a list of blocks (headings, text, code, tables, figures), built
once from the model and its runs; each format renders the same blocks.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field

from ...result import Run
from ...unparse import expr_text
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


@dataclass(frozen=True)
class TableBlock:
    table: T.Table


@dataclass(frozen=True)
class Figure:
    path: str
    caption: str


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


def build(model, runs: Sequence[Run], figures: Sequence[tuple[str, str]], path: str,
          lang: str, checks: Sequence | None = None) -> Document:
    """The report of `model` (an api.Model) and its runs; `figures` are (PNG path,
    caption) pairs; `checks` each run's accuracy check, if made."""
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
        doc.add(*(Text(w) for w in run.warnings))
        if checks is not None and k <= len(checks):
            check = checks[k - 1]
            doc.add(Text(words["accuracy"] + (f" ({check.how})" if check.how else ""),
                         strong=True),
                    *(Text(line) for line in W.accuracy_lines(check, words)))
        if not run.ok:
            doc.add(Text(f"{words['partial']}: {run.message}", strong=True))
    if figures:
        doc.add(Heading(words["plots"], 2), *(Figure(p, c) for p, c in figures))
    return doc
