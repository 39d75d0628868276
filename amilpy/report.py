"""`amilpy report`: everything of a lab report but the conclusions, for one model.

The document holds the TITLE, the listing with line numbers, every data and
INITIAL value (name, value, where defined), the equations in the order the
compiler evaluates them, the printout and RANGE tables, the switching events
and the plots. Formats: Markdown with PNGs, PDF (drawn by matplotlib, no other
dependency) and LaTeX (booktabs tables) for students who write in LaTeX.
"""

from __future__ import annotations

import io
import math
import os

from . import ir
from .printout import atomic_write, format_run, printed_names, report_names
from .result import Run
from .unparse import expr_text

FORMATS = ("md", "pdf", "tex")


def equation_lines(model: ir.Model) -> list[tuple[str, str]]:
    """(section, equation) in evaluation order: INITIAL, then DYNAMIC's algebraic
    equations as sorted, then the state derivatives."""
    out = [("INITIAL", f"{e.target} = {expr_text(model, e.expr)}") for e in model.initial]
    out += [("DYNAMIC", f"{e.target} = {expr_text(model, e.expr)}") for e in model.dynamic]
    for s in model.states:
        out.append(("DYNAMIC", f"d{s.name}/dt = {expr_text(model, s.deriv)}    "
                               f"({s.name}(0) = {expr_text(model, s.ic)})"))
    return out


def data_rows(model: ir.Model, run: Run) -> list[tuple[str, str, str]]:
    """(name, value, where defined) for every data and INITIAL value."""
    rows = []
    for name in model.data_names:
        span = model.spans.get(name)
        where = f"{model.data_kinds.get(name, 'PARAM')}, line {span.line}" if span else ""
        rows.append((name, f"{run.constants.get(name, math.nan):.6g}", where))
    for e in model.initial:
        rows.append((e.target, f"{run.constants.get(e.target, math.nan):.6g}",
                     f"INITIAL, line {e.span.line}"))
    return rows


# --------------------------------------------------------------------- builder

class Report:
    def __init__(self, model, runs: list[Run], figures: list[str], path: str) -> None:
        self.model = model
        self.ir: ir.Model = model.ir
        self.runs = runs
        self.figures = figures
        self.path = path
        self.title = (runs[0].titles[0] if runs and runs[0].titles
                      else os.path.basename(path))
        self.listing = self.ir.source.splitlines()

    # Markdown -----------------------------------------------------------------
    def markdown(self, out_dir: str) -> str:
        md = io.StringIO()
        md.write(f"# {self.title}\n\n")
        for t in self.runs[0].titles[1:]:
            md.write(f"{t}  \n")
        md.write(f"Model file: `{os.path.basename(self.path)}`\n\n## Listing\n\n```amil\n")
        width = len(str(len(self.listing)))
        for i, line in enumerate(self.listing, start=1):
            md.write(f"{i:>{width}}  {line}\n")
        md.write("```\n\n## Data and initial values\n\n| name | value | defined |\n"
                 "|---|---:|---|\n")
        for name, value, where in data_rows(self.ir, self.runs[0]):
            md.write(f"| {name} | {value} | {where} |\n")
        md.write("\n## Equations as evaluated\n\n```\n")
        for section, text in equation_lines(self.ir):
            md.write(f"{section:8} {text}\n")
        md.write("```\n")
        for k, run in enumerate(self.runs, start=1):
            md.write(f"\n## Run {k}: {run.label}\n\n")
            md.write(self._md_table(run))
            ranged = report_names(run, "RANGE")
            if ranged:
                md.write("\n| RANGE | minimum | time | maximum | time |\n"
                         "|---|---:|---:|---:|---:|\n")
                rng = run.range
                for n in ranged:
                    lo, tlo, hi, thi = rng.get(n, (math.nan,) * 4)
                    md.write(f"| {n} | {lo:.6g} | {tlo:.6g} | {hi:.6g} | {thi:.6g} |\n")
            if run.events:
                md.write(f"\nSwitching events ({len(run.events)}):\n\n| TIME | switch | branch |\n"
                         "|---:|---|---|\n")
                for e in run.events[:60]:
                    md.write(f"| {e.time:.9g} | {e.switch} | {e.describe_branch(e.old)} → "
                             f"{e.describe_branch(e.new)} |\n")
                if len(run.events) > 60:
                    md.write(f"\n… and {len(run.events) - 60} more.\n")
            for w in run.warnings:
                md.write(f"\n> {w}\n")
            if not run.ok:
                md.write(f"\n**Partial results:** {run.message}\n")
        if self.figures:
            md.write("\n## Plots\n\n")
            for fig in self.figures:
                rel = os.path.relpath(fig, out_dir)
                md.write(f"![{os.path.basename(fig)}]({rel})\n\n")
        return md.getvalue()

    @staticmethod
    def _md_table(run: Run) -> str:
        names = printed_names(run)
        table = run.printout
        out = "| TIME | " + " | ".join(names) + " |\n|" + "---:|" * (len(names) + 1) + "\n"
        for i, t in enumerate(table.t):
            vals = [table.columns[n][i] if n in table.columns else run.constants.get(n, math.nan)
                    for n in names]
            out += f"| {t:.6g} | " + " | ".join(f"{v:.6E}" for v in vals) + " |\n"
        return out

    # LaTeX --------------------------------------------------------------------
    def latex(self, out_dir: str) -> str:
        tex = io.StringIO()
        tex.write("\\documentclass[a4paper,10pt]{article}\n\\usepackage[utf8]{inputenc}\n"
                  "\\usepackage[T1]{fontenc}\n\\usepackage{lmodern}\n\\usepackage{booktabs}\n"
                  "\\usepackage{longtable}\n\\usepackage{graphicx}\n\\usepackage{fancyvrb}\n"
                  "\\usepackage{color}\n\\usepackage[margin=2cm]{geometry}\n")
        from .highlight import highlight_listing, style_defs

        # the listing goes through the AMIL lexer (coloured when Pygments is there)
        tex.write(style_defs("latex") + "\n\\begin{document}\n")
        tex.write(f"\\section*{{{_tex(self.title)}}}\n\\subsection*{{Listing}}\n")
        tex.write(highlight_listing("\n".join(self.listing) + "\n", "latex", linenos=True))
        tex.write("\\subsection*{Data and initial values}\n\\begin{longtable}{lrl}\n\\toprule\n"
                  "Name & Value & Defined \\\\\n\\midrule\n")
        for name, value, where in data_rows(self.ir, self.runs[0]):
            tex.write(f"{_tex(name)} & {value} & {_tex(where)} \\\\\n")
        tex.write("\\bottomrule\n\\end{longtable}\n")
        tex.write("\\subsection*{Equations as evaluated}\n\\begin{Verbatim}[fontsize=\\small]\n")
        tex.write("\n".join(f"{s:8} {t}" for s, t in equation_lines(self.ir)) +
                  "\n\\end{Verbatim}\n")
        for k, run in enumerate(self.runs, start=1):
            tex.write(f"\\subsection*{{Run {k}: {_tex(run.label)}}}\n")
            names = printed_names(run)
            table = run.printout
            tex.write("\\begin{longtable}{" + "r" * (len(names) + 1) + "}\n\\toprule\n")
            tex.write(" & ".join(["TIME"] + [_tex(n) for n in names]) + " \\\\\n\\midrule\n")
            for i, t in enumerate(table.t):
                vals = [table.columns[n][i] if n in table.columns
                        else run.constants.get(n, math.nan) for n in names]
                tex.write(" & ".join([f"{t:.6g}"] + [f"{v:.6E}" for v in vals]) + " \\\\\n")
            tex.write("\\bottomrule\n\\end{longtable}\n")
            ranged = report_names(run, "RANGE")
            if ranged:
                tex.write("\\begin{tabular}{lrrrr}\n\\toprule\nRANGE & Minimum & Time & Maximum "
                          "& Time \\\\\n\\midrule\n")
                for n in ranged:
                    lo, tlo, hi, thi = run.range.get(n, (math.nan,) * 4)
                    tex.write(f"{_tex(n)} & {lo:.6g} & {tlo:.6g} & {hi:.6g} & {thi:.6g} \\\\\n")
                tex.write("\\bottomrule\n\\end{tabular}\n\n")
            if run.events:
                tex.write(f"\\paragraph{{Switching events ({len(run.events)})}}\n"
                          "\\begin{longtable}{rll}\n\\toprule\nTIME & Switch & Branch \\\\\n"
                          "\\midrule\n")
                for e in run.events[:60]:
                    tex.write(f"{e.time:.9g} & {_tex(e.switch)} & "
                              f"{_tex(e.describe_branch(e.old))} $\\to$ "
                              f"{_tex(e.describe_branch(e.new))} \\\\\n")
                tex.write("\\bottomrule\n\\end{longtable}\n")
            if not run.ok:
                tex.write(f"\\textbf{{Partial results:}} {_tex(run.message)}\n\n")
        for fig in self.figures:
            rel = os.path.relpath(fig, out_dir)
            tex.write("\\begin{figure}[h]\\centering\n"
                      f"\\includegraphics[width=0.9\\textwidth]{{{rel}}}\n\\end{{figure}}\n")
        tex.write("\\end{document}\n")
        return tex.getvalue()

    # PDF ------------------------------------------------------------------------
    def text_pages(self) -> list[list[str]]:
        """The report as monospaced text, cut into pages."""
        lines = [self.title, "=" * min(len(self.title), 90), "", "LISTING", ""]
        width = len(str(len(self.listing)))
        lines += [f"{i:>{width}}  {line}" for i, line in enumerate(self.listing, start=1)]
        lines += ["", "DATA AND INITIAL VALUES", ""]
        lines += [f"{n:<12}{v:>16}   {w}" for n, v, w in data_rows(self.ir, self.runs[0])]
        lines += ["", "EQUATIONS AS EVALUATED", ""]
        lines += [f"{s:8} {t}" for s, t in equation_lines(self.ir)]
        for k, run in enumerate(self.runs, start=1):
            lines += ["", f"RUN {k}: {run.label}", ""]
            lines += format_run(run, k, len(self.runs)).splitlines()
        per_page = 66
        return [lines[i:i + per_page] for i in range(0, len(lines), per_page)]

    def pdf(self, path: str) -> int:
        import matplotlib

        matplotlib.use("Agg", force=True)
        import matplotlib.pyplot as plt
        from matplotlib.backends.backend_pdf import PdfPages

        buf = io.BytesIO()
        pages = 0
        with PdfPages(buf) as pdf:
            for page in self.text_pages():
                fig = plt.figure(figsize=(8.27, 11.69))  # A4
                fig.text(0.06, 0.965, "\n".join(line[:110] for line in page),
                         family="DejaVu Sans Mono", fontsize=6.6, va="top")
                pdf.savefig(fig)
                plt.close(fig)
                pages += 1
            for fig_path in self.figures:
                image = plt.imread(fig_path)
                fig = plt.figure(figsize=(8.27, 11.69))
                ax = fig.add_axes([0.05, 0.35, 0.9, 0.6])
                ax.imshow(image)
                ax.axis("off")
                pdf.savefig(fig)
                plt.close(fig)
                pages += 1
        atomic_write(path, buf.getvalue())
        return pages


def _tex(text: str) -> str:
    for a, b in (("\\", "\\textbackslash{}"), ("&", "\\&"), ("%", "\\%"), ("$", "\\$"),
                 ("#", "\\#"), ("_", "\\_"), ("{", "\\{"), ("}", "\\}"), ("~", "\\~{}"),
                 ("^", "\\^{}")):
        text = text.replace(a, b)
    return text


def make_report(path: str, out_dir: str | None = None, formats=("md",),
                method: str | None = None, **params: float) -> dict[str, str]:
    """Run the model and write its report; returns {format: path written}."""
    from .api import load
    from .plot import plot_runs

    model = load(path)
    runs = model.run(method=method, **params)
    stem = os.path.splitext(os.path.basename(path))[0]
    out_dir = out_dir or os.path.dirname(os.path.abspath(path))
    os.makedirs(out_dir, exist_ok=True)
    figures = plot_runs(runs, out_dir, stem, show=False)
    report = Report(model, runs, figures, path)
    written = {}
    for fmt in formats:
        if fmt == "md":
            target = os.path.join(out_dir, f"{stem}_report.md")
            atomic_write(target, report.markdown(out_dir).encode("utf-8"))
        elif fmt == "tex":
            target = os.path.join(out_dir, f"{stem}_report.tex")
            atomic_write(target, report.latex(out_dir).encode("utf-8"))
        elif fmt == "pdf":
            target = os.path.join(out_dir, f"{stem}_report.pdf")
            report.pdf(target)
        else:
            raise ValueError(fmt)
        written[fmt] = target

    return written
