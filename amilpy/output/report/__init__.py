"""`amilpy report`: everything of a lab report but the conclusions, for one model.

The document holds the TITLE, the listing with line numbers, every data and
INITIAL value (with its unit and description from the `!` comment on its line,
and where it is defined), the equations in the order the compiler evaluates
them, and per run the printout, printer plots, RANGE, events and TERMINAL
values; then the figures with captions. It is built once (`document.build`) and
rendered by each format of `FORMATS`: Markdown with PNGs, PDF (matplotlib) and
LaTeX (a body to `\\input` plus a document around it). Headings are in the
listing's language (`--lang pl|en`). A report of a failed run is written, marked
partial at its top.

Standard library only at import (the command line reads `FORMATS` for its help).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..files import OutputError, atomic_open, ensure_directory
from ..options import PlotOptions

if TYPE_CHECKING:
    from ...result import Run
    from .document import Document


REPORT_FIGURE_HEIGHT = 4.2  # inches, by 8 wide


@dataclass(frozen=True)
class Format:
    name: str
    help: str
    write: Callable[[Document, str, str], list[str]]  # (document, out_dir, stem) -> paths


def _markdown(doc: Document, out_dir: str, stem: str) -> list[str]:
    from . import markdown

    path = os.path.join(out_dir, f"{stem}_report.md")
    with atomic_open(path, text=True, newline="\n") as fh:
        markdown.render(doc, out_dir, fh)
    return [path]


def _latex(doc: Document, out_dir: str, stem: str) -> list[str]:
    from . import latex

    body = os.path.join(out_dir, f"{stem}_report_body.tex")
    path = os.path.join(out_dir, f"{stem}_report.tex")
    latex.check_file_name(stem, path)
    with atomic_open(body, text=True, newline="\n") as fh:
        latex.body(doc, out_dir, fh)
    with atomic_open(path, text=True, newline="\n") as fh:
        latex.document(doc, f"{stem}_report_body", fh)
    return [path, body]


def _pdf(doc: Document, out_dir: str, stem: str) -> list[str]:
    from . import pdf

    path = os.path.join(out_dir, f"{stem}_report.pdf")
    pdf.render(doc, path)
    return [path]


# One row per report format: `--format` and its help are made from it.
FORMATS: dict[str, Format] = {
    "md": Format("md", "Markdown, the figures as PNGs beside it", _markdown),
    "pdf": Format("pdf", "PDF (A4), drawn by matplotlib", _pdf),
    "tex": Format("tex", "LaTeX: NAME_report_body.tex to \\input, and "
                         "NAME_report.tex around it", _latex),
}


def write_report(model, runs: Sequence[Run], path: str, out_dir: str | None = None,
                 formats: Sequence[str] = ("md",), lang: str | None = None,
                 plot_options: PlotOptions | None = None,
                 errors: list[OutputError] | None = None,
                 checks: Sequence | None = None) -> dict[str, list[str]]:
    """Draw the figures and write the report of `runs` in each format; returns
    {format: paths written}. With `errors` given, an output that cannot be
    written is recorded there and the others are still written. `checks`: the
    runs' accuracy checks (`Model.check_accuracy`), a section under each run."""
    from dataclasses import replace

    from .. import words as W
    from ..plot import plot_figures
    from .document import Figure, build

    stem = os.path.splitext(os.path.basename(path))[0]
    out_dir = ensure_directory(out_dir or os.path.dirname(os.path.abspath(path)))
    if lang is None:
        labels = [r.label or "" for r in runs[0].reports] if runs else []
        lang = W.detect_language([*(runs[0].titles if runs else []), *labels])
    words = W.WORDS[lang]
    written: dict[str, list[str]] = {}

    def attempt(what: Callable[[], list], key: str | None = None) -> list:
        try:
            done = what()
        except OutputError as exc:
            if errors is None:
                raise
            errors.append(exc)
            return []
        if key is not None:
            written[key] = done
        return done

    # (PNG for Markdown, PDF for LaTeX; the PDF report draws them again on its pages;
    # a little less tall than on screen, so that two share a page with some text)
    options = replace(plot_options or PlotOptions(), formats=("png", "pdf"),
                      height=REPORT_FIGURE_HEIGHT)
    saved = attempt(lambda: plot_figures(list(runs), out_dir, stem, options,
                                         W.name_notes(model.ir), words))
    figures = [Figure(f.paths[0], f.caption, f.paths[1], f.redraw, f.size) for f in saved]
    doc = build(model, runs, figures, path, lang, checks)
    for fmt in formats:
        attempt(lambda fmt=fmt: FORMATS[fmt].write(doc, out_dir, stem), fmt)
    return written


def make_report(path: str, out_dir: str | None = None, formats: Sequence[str] = ("md",),
                method: str | None = None, lang: str | None = None,
                plot_options: PlotOptions | None = None, **params: float) -> dict[str, str]:
    """Run the model and write its report; returns {format: main path written}."""
    from ...api import load

    model = load(path)
    runs = model.run(method=method, **params)
    written = write_report(model, runs, path, out_dir, formats, lang, plot_options)
    return {fmt: paths[0] for fmt, paths in written.items()}
