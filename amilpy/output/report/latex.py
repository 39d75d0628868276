"""The report in LaTeX: a body to `\\input` into your own document, and a small
document around it that compiles on its own, in one pdflatex run, with the
packages of a standard TeX Live's latex-base and latex-recommended (lmodern is
used where it is installed).

The body (`NAME_report_body.tex`) has no preamble. It needs booktabs, longtable,
array, graphicx, fancyvrb and color in the including document; from another
folder include it with the import package (`\\subimport{report/}{NAME_report_body}`)
so that its figures are found. Nothing is wider than the text: a listing or
equation line longer than `CODE_CHARS` goes on in the next row, marked; a table's
columns have fixed widths (so longtable needs no second run), as many side by
side as fit, the first column starting each part; a long text cell wraps.
Figures are the PDF (vector) files, the text's width, captioned.
"""

from __future__ import annotations

import os
import unicodedata
from typing import TextIO

from .. import tables as T
from ..files import OutputError
from ..highlight import VERBATIM, verbatim
from ..words import visible
from .document import CODE_CHARS, CONTINUED, Code, Document, Figure, Heading, TableBlock, Text

PACKAGES = ("booktabs", "longtable", "array", "graphicx", "fancyvrb", "color")
TEXT_PT = 483.0  # the text width of the document around the body (A4, 2 cm margins)
SEP_PT = 3.0  # a table column's separation on each side
FIGURE_WIDTH = 0.75  # of the text's: two figures and their captions share a page
FOOTNOTE_PT = 8.0  # \footnotesize in a 10-point document
OPTICAL = 1.08
# Computer Modern's widths, in em, of what tables hold (digits and most lower case
# are half an em at 10 pt; the 8-point design is 7 % wider, `OPTICAL`); a little
# over, so that a column is never narrower than its cells
_EM = {**dict.fromkeys("0123456789*/?$", 0.5), **dict.fromkeys(".,:;!'", 0.28),
       **dict.fromkeys("-()[] ", 0.39), **dict.fromkeys("+=<>", 0.78),
       **dict.fromkeys("mwMW", 1.03), **dict.fromkeys("ABCDEFGHIJKLNOPQRSTUVXYZ", 0.75)}
_SPECIAL = {"\\": "\\textbackslash{}", "&": "\\&", "%": "\\%", "$": "\\$", "#": "\\#",
            "_": "\\_", "{": "\\{", "}": "\\}", "~": "\\~{}", "^": "\\^{}", "<": "$<$",
            ">": "$>$", "…": "\\dots{}", "→": "$\\to$", "≤": "$\\le$", "≥": "$\\ge$",
            "µ": "\\textmu{}", "°": "\\textdegree{}"}


def tex(text: str) -> str:
    """Text for LaTeX: special characters escaped, Greek letters as math (pdflatex
    has no glyphs for them in T1 text), control characters as "?"."""
    out = []
    for ch in visible(text):
        if ch in _SPECIAL:
            out.append(_SPECIAL[ch])
        elif "\u0391" <= ch <= "\u03c9":
            out.append(_greek(ch))
        else:
            out.append(ch)
    return "".join(out)


# Greek capitals that look like Latin ones have no LaTeX macro: the Latin letter is it.
_LATIN_LOOKALIKE = {"Alpha": "A", "Beta": "B", "Epsilon": "E", "Zeta": "Z", "Eta": "H",
                    "Iota": "I", "Kappa": "K", "Mu": "M", "Nu": "N", "Omicron": "O",
                    "Rho": "P", "Tau": "T", "Chi": "X", "omicron": "o"}


def _greek(ch: str) -> str:
    words = unicodedata.name(ch, "").split()
    if len(words) < 4:
        return "?"
    letter = words[-1].lower().replace("lamda", "lambda")
    if words[1] == "CAPITAL":
        letter = letter.capitalize()
    if letter in _LATIN_LOOKALIKE:
        return _LATIN_LOOKALIKE[letter]
    return f"\\ensuremath{{\\{letter}}}"


def text_width(text: str, size: float = FOOTNOTE_PT) -> float:
    """What `text` takes set in Computer Modern at `size` points, near enough."""
    return size * OPTICAL * sum(_EM.get(ch, 0.55) for ch in text)


def _natural_widths(t: T.Table) -> list[float]:
    """The widest cell (or header) of each column, in points."""
    out = [text_width(c.name) for c in t.columns]
    for block in t.blocks():
        for k, cells in enumerate(block):
            if cells:
                out[k] = max(out[k], max(text_width(v) for v in cells))
    return [w + 1.0 for w in out]


def column_blocks(t: T.Table) -> list[list[tuple[int, float]]]:
    """The table's columns as parts that fit the text width side by side: (column,
    width in points) each, the first column starting every part; a column too wide
    for any part (a long text) gets what is left and wraps."""
    pts = _natural_widths(t)
    first = min(pts[0], TEXT_PT / 2)
    blocks: list[list[tuple[int, float]]] = [[(0, first)]]
    used = first + 2 * SEP_PT
    for k in range(1, len(pts)):
        need = pts[k] + 2 * SEP_PT
        if used + need > TEXT_PT and len(blocks[-1]) > 1:
            blocks.append([(0, first)])
            used = first + 2 * SEP_PT
        width = min(pts[k], TEXT_PT - used - 2 * SEP_PT)
        blocks[-1].append((k, width))
        used += width + 2 * SEP_PT
    return blocks


def table(t: T.Table, out: TextIO) -> None:
    if t.caption:
        out.write(f"\\paragraph*{{{tex(t.caption)}}}\n")
    for block in column_blocks(t):
        cols = [t.columns[k] for k, _ in block]
        spec = "".join(
            f">{{\\raggedright\\arraybackslash}}p{{{w:.1f}pt}}" if c.left else
            f">{{\\raggedleft\\arraybackslash}}p{{{w:.1f}pt}}"
            for c, (_, w) in zip(cols, block, strict=True))
        head = " & ".join(tex(c.name) for c in cols) + " \\\\\n"
        out.write(f"{{\\footnotesize\\setlength{{\\tabcolsep}}{{{SEP_PT:g}pt}}"
                  "\\renewcommand{\\arraystretch}{0.95}"
                  f"\\setlength{{\\LTpre}}{{4pt}}\\setlength{{\\LTpost}}{{4pt}}"
                  f"\\begin{{longtable}}{{@{{}}{spec}@{{}}}}\n\\toprule\n{head}\\midrule\n"
                  "\\endhead\n\\bottomrule\n\\endfoot\n")
        for row in t.rows(cols):
            out.write(" & ".join(tex(v) for v in row) + " \\\\\n")
        out.write("\\end{longtable}}\n")
    for note in t.notes:
        out.write(f"{tex(note)}\n\n")


# What TeX reads as markup in a file name given to \input or \includegraphics
# (where it cannot be escaped): a listing's name with one of them would run commands.
_NOT_IN_NAMES = set("\\{}%#$&^~")


def check_file_name(stem: str, path: str) -> None:
    """Refuse a listing's name that the LaTeX files would have to name raw."""
    bad = sorted({ch for ch in stem if ch in _NOT_IN_NAMES or visible(ch) != ch})
    if bad:
        raise OutputError(path, f"the listing's name {visible(stem)!r} has "
                          f"{' '.join(visible(ch) for ch in bad)}, which LaTeX would read "
                          "as commands in the file names the report gives it: copy the "
                          "listing to a name without them")


# the continuation mark of a code row, in the Verbatim's commandchars
_MARK = "\\ensuremath{\\hookrightarrow}"


def code(b: Code, out: TextIO) -> None:
    """A listing (numbered, highlighted where Pygments is installed) or equations,
    `CODE_CHARS` wide: a longer line goes on in the next row, marked."""
    from ..highlight import latex_pieces

    if b.kind == "plot":
        verbatim(b.lines, out)
        return
    rows = b.rows(CODE_CHARS)
    lines = [visible(line) for line in b.lines]
    texts = (latex_pieces(lines, [(r.line, r.start, len(r.text)) for r in rows])
             if b.kind == "listing" else None)
    if texts is None:
        texts = [visible(r.text).translate(VERBATIM) for r in rows]
    out.write("\\begin{Verbatim}[commandchars=\\\\\\{\\},fontsize=\\small]\n")
    for r, text in zip(rows, texts, strict=True):
        gutter = r.gutter.replace(CONTINUED, _MARK)
        out.write(f"{gutter}{text}\n")
    out.write("\\end{Verbatim}\n")


def body(doc: Document, out_dir: str, out: TextIO) -> None:
    from ..highlight import style_defs

    out.write(f"% amilpy report: {tex(doc.title)}\n"
              f"% needs \\usepackage{{{','.join(PACKAGES)}}}\n")
    # the listing's colours (Pygments' macros): definitions, allowed in a body
    out.write(style_defs("latex") + "\n")
    for b in doc.blocks:
        if isinstance(b, Heading):
            command = {1: "section", 2: "subsection"}.get(b.level, "subsubsection")
            # (ragged right: a long TITLE in capitals has few places to hyphenate)
            out.write(f"\\{command}*{{\\raggedright {tex(b.text)}}}\n")
        elif isinstance(b, Text):
            out.write(f"\\textbf{{{tex(b.text)}}}\n\n" if b.strong else f"{tex(b.text)}\n\n")
        elif isinstance(b, Code):
            code(b, out)
        elif isinstance(b, TableBlock):
            table(b.table, out)
        elif isinstance(b, Figure):
            rel = os.path.relpath(b.vector or b.path, out_dir).replace(os.sep, "/")
            out.write("\\begin{figure}[htbp]\\centering\n"
                      f"\\includegraphics[width={FIGURE_WIDTH}\\linewidth]{{{rel}}}\n"
                      f"\\caption{{{tex(b.caption)}}}\n\\end{{figure}}\n")
        else:  # pragma: no cover - every block kind is rendered above
            raise TypeError(type(b).__name__)


def document(doc: Document, body_name: str, out: TextIO) -> None:
    """A whole document that `\\input`s the body: one pdflatex run makes it (no
    reference to resolve, table widths fixed)."""
    out.write("\\documentclass[a4paper,10pt]{article}\n\\usepackage[utf8]{inputenc}\n"
              "\\usepackage[T1]{fontenc}\n"
              # (lmodern's scalable fonts where installed; else the EC fonts)
              "\\IfFileExists{lmodern.sty}{\\usepackage{lmodern}}{}\n"
              + "".join(f"\\usepackage{{{p}}}\n" for p in PACKAGES)
              + "\\usepackage[margin=2cm]{geometry}\n"
              "\\setlength{\\parindent}{0pt}\\setlength{\\parskip}{3pt}\n"
              # figures may fill a page with text around them: fewer, fuller pages
              "\\renewcommand{\\topfraction}{0.9}\\renewcommand{\\bottomfraction}{0.9}\n"
              "\\renewcommand{\\textfraction}{0.07}\\renewcommand{\\floatpagefraction}{0.8}\n"
              "\\setcounter{totalnumber}{4}\\setcounter{topnumber}{3}\n")
    if doc.lang == "pl":
        out.write("\\renewcommand{\\figurename}{Rys.}\n\\renewcommand{\\tablename}{Tabela}\n")
    out.write(f"\\begin{{document}}\n\\input{{{body_name}}}\n\\end{{document}}\n")
