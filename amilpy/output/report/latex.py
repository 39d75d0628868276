"""The report in LaTeX: a body to `\\input` into your own document, and a small
document around it that compiles on its own.

The body (`NAME_report_body.tex`) has no preamble. It needs booktabs, longtable,
graphicx, fancyvrb and color in the including document; from another folder
include it with the import package (`\\subimport{report/}{NAME_report_body}`) so
that its figures are found. Tables are longtables (they break across pages and
repeat their header), wide ones split by columns; figures have captions.
"""

from __future__ import annotations

import os
import unicodedata
from typing import TextIO

from .. import tables as T
from ..files import OutputError
from ..words import visible
from .document import Code, Document, Figure, Heading, TableBlock, Text

PACKAGES = ("booktabs", "longtable", "graphicx", "fancyvrb", "color")
COLUMNS = 8  # value columns of one longtable; wider tables go on in another
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


def table(t: T.Table, out: TextIO) -> None:
    first, rest = t.columns[0], t.columns[1:]
    blocks = [rest[i:i + COLUMNS] for i in range(0, len(rest), COLUMNS)] or [[]]
    if t.caption:
        out.write(f"\\paragraph*{{{tex(t.caption)}}}\n")
    for block in blocks:
        cols = [first, *block]
        spec = "".join("l" if c.left else "r" for c in cols)
        head = " & ".join(tex(c.name) for c in cols) + " \\\\\n"
        # seven E-format columns need a smaller font to fit a 17 cm text width
        size = "" if len(cols) < 6 else "\\small" if len(cols) < 8 else "\\footnotesize"
        out.write(f"{{{size}\\begin{{longtable}}{{{spec}}}\n\\toprule\n{head}\\midrule\n"
                  "\\endhead\n\\bottomrule\n\\endfoot\n")
        for row in t.rows(cols):
            out.write(" & ".join(tex(v) for v in row) + " \\\\\n")
        out.write("\\end{longtable}}\n")
    for note in t.notes:
        out.write(f"{tex(note)}\n\n")


# In a Verbatim with commandchars, a listing's text can neither end the environment
# (a line "\end{Verbatim}") nor run a command: its \, { and } are characters by number.
_VERBATIM = str.maketrans({"\\": "\\char92{}", "{": "\\char123{}", "}": "\\char125{}"})


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


def verbatim(lines: list[str], out: TextIO, options: str = "") -> None:
    """Lines as they are, in a fancyvrb Verbatim (`options` after its own)."""
    longest = max((len(line) for line in lines), default=0)
    size = "\\small" if longest <= 90 else "\\scriptsize" if longest <= 125 else "\\tiny"
    out.write(f"\\begin{{Verbatim}}[commandchars=\\\\\\{{\\}},fontsize={size}{options}]\n")
    out.write("".join(visible(line).translate(_VERBATIM) + "\n" for line in lines))
    out.write("\\end{Verbatim}\n")


def body(doc: Document, out_dir: str, out: TextIO) -> None:
    from ...highlight import highlight_listing, style_defs

    out.write(f"% amilpy report: {tex(doc.title)}\n"
              f"% needs \\usepackage{{{','.join(PACKAGES)}}}\n")
    # the listing's colours (Pygments' macros): definitions, allowed in a body
    out.write(style_defs("latex") + "\n")
    for b in doc.blocks:
        if isinstance(b, Heading):
            command = {1: "section", 2: "subsection"}.get(b.level, "subsubsection")
            out.write(f"\\{command}*{{{tex(b.text)}}}\n")
        elif isinstance(b, Text):
            out.write(f"\\textbf{{{tex(b.text)}}}\n\n" if b.strong else f"{tex(b.text)}\n\n")
        elif isinstance(b, Code) and b.kind == "listing":  # (without Pygments: `verbatim`)
            out.write(highlight_listing(visible("\n".join(b.lines)) + "\n", "latex",
                                        linenos=True))
        elif isinstance(b, Code):
            verbatim(b.lines, out)
        elif isinstance(b, TableBlock):
            table(b.table, out)
        elif isinstance(b, Figure):
            rel = os.path.relpath(b.path, out_dir).replace(os.sep, "/")
            out.write("\\begin{figure}[htbp]\\centering\n"
                      f"\\includegraphics[width=0.9\\linewidth]{{{rel}}}\n"
                      f"\\caption{{{tex(b.caption)}}}\n\\end{{figure}}\n")
        else:  # pragma: no cover - every block kind is rendered above
            raise TypeError(type(b).__name__)


def document(doc: Document, body_name: str, out: TextIO) -> None:
    """A whole document that `\\input`s the body."""
    out.write("\\documentclass[a4paper,10pt]{article}\n\\usepackage[utf8]{inputenc}\n"
              "\\usepackage[T1]{fontenc}\n\\usepackage{lmodern}\n"
              + "".join(f"\\usepackage{{{p}}}\n" for p in PACKAGES)
              + "\\usepackage[margin=2cm]{geometry}\n")
    if doc.lang == "pl":
        out.write("\\renewcommand{\\figurename}{Rys.}\n\\renewcommand{\\tablename}{Tabela}\n")
    out.write(f"\\begin{{document}}\n\\input{{{body_name}}}\n\\end{{document}}\n")
