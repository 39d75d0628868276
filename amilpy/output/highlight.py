"""Syntax highlighting of AMIL listings: a Pygments lexer and a helper for reports.

Pygments is optional. It is imported only here, so the rest of amilpy never
needs it; `highlight_listing` falls back to unhighlighted text without it.
The lexer is registered for `pygmentize`, Sphinx and Jupyter through the
`pygments.lexers` entry point (`amil = "amilpy.output.highlight:AmilLexer"`).

The token rules follow grammar/amil.lark and amilpy/parse/; the function and
reserved names are read from amilpy.library and amilpy.language at import, so the
highlighter never disagrees with what the compiler accepts. The TextMate
grammar in editors/vscode/ mirrors these rules (tests/test_highlight.py keeps
the two lists of names in step).
"""

from __future__ import annotations

import html
import re
from typing import Any, TextIO

# Absolute imports: `pygmentize -x -l amilpy/output/highlight.py:AmilLexer` runs this
# file outside its package, where relative imports fail.
from amilpy.language import RESERVED, STATEMENT_KEYWORDS
from amilpy.library import callable_names
from amilpy.output.words import visible

# Statement and section keywords (amilpy.language). TITLE and LABEL are handled
# apart because their free text runs to the end of the line.
SECTION_KEYWORDS = ("INITIAL", "DYNAMIC", "DERIVATIVE", "TERMINAL", "END", "STOP")
TEXT_KEYWORDS = ("TITLE", "LABEL")
KEYWORDS = TEXT_KEYWORDS + SECTION_KEYWORDS + STATEMENT_KEYWORDS

# Every name a listing may call, canonical names and aliases alike.
BUILTIN_FUNCTIONS = tuple(sorted(callable_names()))
RESERVED_NAMES = tuple(RESERVED)

FORMATTERS = ("terminal", "html", "latex")

# `...` or `&` is a continuation mark only when nothing but blanks and a `!`
# comment follows it on the line (the rule of parse.blank_comment_lines).
_CONTINUATION = r"(\.\.\.|&)(?=[ \t\f\r]*(?:![^\n]*)?$)"

try:
    from pygments.lexer import RegexLexer, bygroups, default, include, words
    from pygments.token import (
        Comment,
        Error,
        Generic,
        Keyword,
        Name,
        Number,
        Operator,
        Punctuation,
        String,
        Whitespace,
    )
except ImportError:  # pragma: no cover - exercised only without pygments
    AmilLexer = None
else:

    class AmilLexer(RegexLexer):
        """Pygments lexer for AMIL / CSMP III simulation listings (`*.amil`)."""

        name = "AMIL"
        aliases = ["amil", "csmp"]
        filenames = ["*.amil", "*.csl", "*.fst"]  # (the ACSL and FST forms too)
        mimetypes = ["text/x-amil"]
        # Keywords and names are case-insensitive in the language, so the whole
        # lexer is; MULTILINE lets `^` and `$` see line boundaries.
        flags = re.MULTILINE | re.IGNORECASE

        @staticmethod
        def analyse_text(text: str) -> float:
            """How much `text` looks like a listing (Pygments' guess between lexers
            that share an extension: .fst is F*'s too)."""
            marks = re.findall(r"^\s*(TIMER|INTGRL|INTEG|DYNAMIC|DERIVATIVE|TERMT|"
                               r"TRANSLATION_GENERAL|STOP|END|PARAM|CONSTANT)\b", text,
                               re.IGNORECASE | re.MULTILINE)
            return min(1.0, 0.3 * len(set(m.upper() for m in marks)))

        def __init__(self, **options: Any) -> None:
            # Pygments strips leading and trailing blank lines by default; a
            # listing printed with line numbers must keep the file's numbering,
            # which the compiler's diagnostics refer to.
            options.setdefault("stripnl", False)
            super().__init__(**options)

        tokens = {
            "root": [
                # A comment line: first non-blank character `*`. Only tried at
                # the start of a line that does not continue a previous one
                # (the `contline` state below has no such rule).
                (r"^([ \t\f\r]*)(\*[^\n]*)", bygroups(Whitespace, Comment.Single)),
                (_CONTINUATION, Punctuation, "cont_tail"),
                include("code"),
                (r"\n", Whitespace),
            ],
            # The rest of a line after a continuation mark: blanks and a comment.
            "cont_tail": [
                (r"[ \t\f\r]+", Whitespace),
                (r"![^\n]*", Comment.Single),
                (r"\n", Whitespace, ("#pop", "contline")),
            ],
            # A continued line: a leading `*` here is multiplication.
            "contline": [
                (_CONTINUATION, Punctuation, ("#pop", "cont_tail")),
                include("code"),
                (r"\n", Whitespace, "#pop"),
            ],
            "code": [
                (r"[ \t\f\r]+", Whitespace),
                (r"![^\n]*", Comment.Single),
                (r"'[^'\n]*'", String.Single),
                (r'"[^"\n]*"', String.Double),
                (r"\b(TITLE)\b", Keyword, "title_text"),
                (r"\b(LABEL)\b", Keyword, "label_text"),
                (words(SECTION_KEYWORDS + STATEMENT_KEYWORDS, prefix=r"\b", suffix=r"\b"),
                 Keyword),
                # A function name is a builtin only when called: a listing may
                # not use it as a variable, but highlighting one as a call
                # would hide the mistake.
                (words(BUILTIN_FUNCTIONS, prefix=r"\b", suffix=r"\b(?=[ \t\f\r]*\()"),
                 Name.Builtin),
                (words(RESERVED_NAMES, prefix=r"\b", suffix=r"\b"), Name.Builtin.Pseudo),
                (r"[a-z][a-z0-9_]*", Name),
                # 12.  .5  1.5E-3  1.5D-3 (D read as E); a `.` followed by `..`
                # is a continuation mark, not a decimal point.
                (r"(?:\d+\.(?!\.\.)\d*|\.\d+)(?:[ed][+-]?\d+)?|\d+[ed][+-]?\d+",
                 Number.Float),
                (r"\d+", Number.Integer),
                (r"\*\*|[-+*/^=]", Operator),
                (r"[(),;$]", Punctuation),
                # Anything else (a letter outside A-Z in code, a stray `.`) is
                # an error in the language too.
                (r"[^\n]", Error),
            ],
            # TITLE / LABEL free text: any script, up to a `!` comment or the
            # end of the line. A trailing continuation mark is still a mark:
            # parse.blank_comment_lines then keeps a following `*` line as code.
            "title_text": [
                (r"[ \t\f\r]+", Whitespace),
                (_CONTINUATION, Punctuation, ("#pop", "cont_tail")),
                (r"[^\n!]+?(?=[ \t\f\r]*(?:\.\.\.|&)[ \t\f\r]*(?:![^\n]*)?$)", Generic.Heading),
                (r"[^\n!]+", Generic.Heading),
                default("#pop"),
            ],
            "label_text": [
                (r"[ \t\f\r]+", Whitespace),
                (_CONTINUATION, Punctuation, ("#pop", "cont_tail")),
                (r"[^\n!]+?(?=[ \t\f\r]*(?:\.\.\.|&)[ \t\f\r]*(?:![^\n]*)?$)", String),
                (r"[^\n!]+", String),
                default("#pop"),
            ],
        }


def _formatter(kind: str, options: dict[str, Any]) -> Any:
    from pygments.formatters import HtmlFormatter, LatexFormatter, TerminalFormatter

    if kind == "html":
        return HtmlFormatter(**options)
    if kind == "latex":
        return LatexFormatter(**options)
    return TerminalFormatter(**options)


def highlight_listing(text: str, formatter: str = "terminal", **options: Any) -> str:
    """A listing highlighted for a terminal, an HTML page or a LaTeX document.

    `options` go to the Pygments formatter (e.g. `linenos=True`). Without
    Pygments the terminal form is the text unchanged; the HTML and LaTeX forms
    keep the shape Pygments gives them (an escaped `<div class="highlight"><pre>`,
    a fancyvrb `Verbatim` environment), so a report can paste either result
    without knowing whether Pygments is installed.
    """
    if formatter not in FORMATTERS:
        raise ValueError(f"formatter must be one of {', '.join(FORMATTERS)}, not {formatter!r}")
    if AmilLexer is None:
        if formatter == "html":
            return f'<div class="highlight"><pre>{html.escape(text)}</pre></div>\n'
        if formatter == "latex":  # (escaped: a line "\\end{Verbatim}" stays text)
            import io

            out = io.StringIO()
            verbatim(text.splitlines(), out, ",numbers=left" if options.get("linenos") else "")
            return out.getvalue()
        return text
    from pygments import highlight

    return highlight(text, AmilLexer(), _formatter(formatter, options))


def latex_pieces(lines: list[str], pieces: list[tuple[int, int, int]]) -> list[str] | None:
    """Each (line index, start, length) piece of `lines` highlighted for LaTeX
    (Pygments' \\PY macros, for a fancyvrb Verbatim with commandchars), the
    listing tokenized whole so a piece broken off a comment is still a comment;
    None without Pygments."""
    if AmilLexer is None:
        return None
    import io

    from pygments.formatters import LatexFormatter

    by_line: list[list[tuple[Any, str]]] = [[]]
    lexer = AmilLexer(stripnl=False)
    for ttype, value in lexer.get_tokens("\n".join(lines) + "\n"):
        for k, part in enumerate(value.split("\n")):
            if k:
                by_line.append([])
            if part:
                by_line[-1].append((ttype, part))
    formatter = LatexFormatter(nowrap=True)
    out = []
    for line, start, length in pieces:
        piece, at = [], 0
        for ttype, value in by_line[line] if line < len(by_line) else []:
            a, b = max(start - at, 0), min(start + length - at, len(value))
            if a < b:
                piece.append((ttype, value[a:b]))
            at += len(value)
        buf = io.StringIO()
        formatter.format(iter(piece), buf)
        out.append(buf.getvalue().rstrip("\n"))
    return out


def style_defs(formatter: str = "html", **options: Any) -> str:
    """The CSS (html) or LaTeX macros (latex) that highlighted output needs.

    Empty without Pygments or for the terminal, where colours are inline.
    """
    if AmilLexer is None or formatter == "terminal":
        return ""
    if formatter not in FORMATTERS:
        raise ValueError(f"formatter must be one of {', '.join(FORMATTERS)}, not {formatter!r}")
    fmt = _formatter(formatter, options)
    if formatter == "html":
        # scoped to the output's <div class="highlight">, so a report page's
        # own styles keep their names
        return fmt.get_style_defs("." + fmt.cssclass)
    return fmt.get_style_defs()


# In a Verbatim with commandchars, a listing's text can neither end the environment
# (a line "\end{Verbatim}") nor run a command: its \, { and } are characters by number.
VERBATIM = str.maketrans({"\\": "\\char92{}", "{": "\\char123{}", "}": "\\char125{}"})


def verbatim(lines: list[str], out: TextIO, options: str = "") -> None:
    """Lines as they are, in a fancyvrb Verbatim (`options` after its own), in a
    font small enough for the longest (a printer plot)."""
    from amilpy.output.report.document import CODE_CHARS  # (what \\small fits)

    longest = max((len(line) for line in lines), default=0)
    size = "\\small" if longest <= CODE_CHARS else "\\scriptsize" if longest <= 125 \
        else "\\tiny"
    out.write(f"\\begin{{Verbatim}}[commandchars=\\\\\\{{\\}},fontsize={size}{options}]\n")
    out.write("".join(visible(line).translate(VERBATIM) + "\n" for line in lines))
    out.write("\\end{Verbatim}\n")
