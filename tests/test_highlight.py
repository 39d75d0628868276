"""Editor support: the Pygments lexer (amilpy/output/highlight.py) and the TextMate grammar
(editors/vscode/) read listings the way amilpy's reader does."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

pytest.importorskip("pygments")

from pygments.token import (  # noqa: E402 - only after the importorskip
    Comment,
    Error,
    Generic,
    Keyword,
    Name,
    Number,
    Operator,
    Punctuation,
    String,
    Token,
)

from amilpy.output.highlight import (  # noqa: E402
    BUILTIN_FUNCTIONS,
    KEYWORDS,
    RESERVED_NAMES,
    AmilLexer,
    highlight_listing,
    style_defs,
)

ROOT = Path(__file__).resolve().parent.parent
LISTINGS = sorted((ROOT / "models").glob("*.amil")) + sorted(
    (ROOT / "tests" / "golden").glob("*.amil"))
EDITOR = ROOT / "editors" / "vscode"
TMGRAMMAR = EDITOR / "syntaxes" / "amil.tmLanguage.json"


def tokens(text: str) -> list[tuple[object, str]]:
    # ensurenl=False: the round trip must give back exactly the input
    return list(AmilLexer(ensurenl=False).get_tokens(text))


def significant(text: str) -> list[tuple[object, str]]:
    return [(t, v) for t, v in tokens(text) if t not in Token.Text.Whitespace and v.strip()]


def test_listings_exist():
    assert len(LISTINGS) >= 6


@pytest.mark.parametrize("path", LISTINGS, ids=lambda p: p.name)
def test_every_listing_tokenizes_without_errors(path):
    text = path.read_text(encoding="utf-8")
    toks = tokens(text)
    errors = [(v, text[: sum(len(w) for _, w in toks[:i])].count("\n") + 1)
              for i, (t, v) in enumerate(toks) if t in Error]
    assert errors == []
    assert "".join(v for _, v in toks) == text


SAMPLE = """\
title Napęd dwumasowy: sprzęgło, źródło żółć
* a comment line: Y = A*B
param k = 1.5D-3, c = 12., b = .5, n = 3
Dynamic
   Y = A + B ...   ! continued
      *C
   Z = INTGRL(0.0, -K*Z**2) + fsw(time - t1, 0.0, 1.0, 1.0)
 * indented comment
Label Prędkość kątowa [rad/s] ! ą in a comment
END
"""


def test_sample_token_classes():
    sig = significant(SAMPLE)
    assert sig[0] == (Keyword, "title")
    assert sig[1] == (Generic.Heading, "Napęd dwumasowy: sprzęgło, źródło żółć")
    assert sig[2] == (Comment.Single, "* a comment line: Y = A*B")
    # keywords in any case
    assert (Keyword, "param") in sig
    assert (Keyword, "Dynamic") in sig
    assert (Keyword, "END") in sig
    assert (Keyword, "Label") in sig
    assert (String, "Prędkość kątowa [rad/s] ") in sig
    assert (Comment.Single, "! ą in a comment") in sig
    # numbers: D exponent, trailing point, leading point, integer
    assert (Number.Float, "1.5D-3") in sig
    assert (Number.Float, "12.") in sig
    assert (Number.Float, ".5") in sig
    assert (Number.Integer, "3") in sig
    # a continued line that starts with `*` is a product, not a comment
    i = sig.index((Punctuation, "..."))
    assert sig[i + 1] == (Comment.Single, "! continued")
    assert sig[i + 2 : i + 4] == [(Operator, "*"), (Name, "C")]
    # ... but the next uncontinued `*` line is a comment again
    assert (Comment.Single, "* indented comment") in sig
    # builtins in any case, reserved names, ** operator
    assert (Name.Builtin, "INTGRL") in sig
    assert (Name.Builtin, "fsw") in sig
    assert (Name.Builtin.Pseudo, "time") in sig
    assert (Operator, "**") in sig
    assert (Name, "t1") in sig
    assert not any(t in Error for t, _ in tokens(SAMPLE))
    assert "".join(v for _, v in tokens(SAMPLE)) == SAMPLE


def test_continuation_marks_and_separators():
    sig = significant("X = 12... ! c\n *Y & \n*Z\n*W\nA = 1; B = MAX(1, 2) $ C = 2^3\n")
    # `12...`: the number ends before the mark
    assert sig[2:4] == [(Number.Integer, "12"), (Punctuation, "...")]
    assert sig[5:7] == [(Operator, "*"), (Name, "Y")]
    assert sig[7] == (Punctuation, "&")
    assert sig[8:10] == [(Operator, "*"), (Name, "Z")]
    assert sig[10] == (Comment.Single, "*W")
    assert (Punctuation, ";") in sig and (Punctuation, "$") in sig
    assert (Name.Builtin, "MAX") in sig and (Operator, "^") in sig


def test_function_name_not_called_is_a_plain_name():
    assert significant("STEP = 1\n")[0] == (Name, "STEP")
    assert significant("Y = STEP (T0)\n")[2] == (Name.Builtin, "STEP")


def test_title_ending_in_a_mark_continues_like_the_reader():
    # parse.blank_comment_lines keeps the `*` line after it as code
    sig = significant("TITLE A ...\n*B\n")
    assert sig == [(Keyword, "TITLE"), (Generic.Heading, "A"), (Punctuation, "..."),
                   (Operator, "*"), (Name, "B")]


def test_leading_blank_lines_are_kept_for_line_numbers():
    text = "\n\nTITLE X\n"
    assert "".join(v for _, v in AmilLexer().get_tokens(text)) == text


def test_names_come_from_the_library():
    from amilpy.language import RESERVED
    from amilpy.library import ALIASES, FUNCTIONS

    # every name a listing may call; `A > B` makes a relational switch (.GT.) no
    # listing can call by name
    written = {n for n in set(FUNCTIONS) | set(ALIASES) if not n.startswith(".")}
    assert set(BUILTIN_FUNCTIONS) == written and ".GT." in FUNCTIONS
    assert set(RESERVED_NAMES) == set(RESERVED)


def test_registered_names():
    assert AmilLexer.name == "AMIL"
    assert set(AmilLexer.aliases) == {"amil", "csmp"}
    # the ACSL (.csl) and FST (.fst) forms are listings amilpy reads too (issue 28.7);
    # the VS Code grammar registers the same extensions
    assert AmilLexer.filenames == ["*.amil", "*.csl", "*.fst"]
    package = json.loads((ROOT / "editors" / "vscode" / "package.json").read_text("utf-8"))
    extensions = package["contributes"]["languages"][0]["extensions"]
    assert extensions == [f.lstrip("*") for f in AmilLexer.filenames]
    from pygments.lexers import get_lexer_for_filename, guess_lexer_for_filename

    for name in ("clutch.amil", "pbpk.csl"):
        assert get_lexer_for_filename(name).name == "AMIL", name
    # (.fst is F*'s too: the text decides, as Pygments' guess does)
    text = (ROOT / "models" / "examples" / "fst_wheat.fst").read_text("utf-8")
    assert guess_lexer_for_filename("sucros.fst", text).name == "AMIL"
    assert guess_lexer_for_filename("proof.fst", "module M\nlet x : int = 1\n").name \
        != "AMIL"


@pytest.mark.parametrize("kind", ["terminal", "html", "latex"])
def test_highlight_listing(kind):
    text = (ROOT / "models" / "ex4_clutch.amil").read_text(encoding="utf-8")
    out = highlight_listing(text, kind)
    assert out != text
    assert "INTGRL" in out
    if kind == "html":
        assert '<div class="highlight">' in out
        assert ".highlight" in style_defs("html")
    if kind == "latex":
        assert "\\begin{Verbatim}" in out
        assert style_defs("latex")


def test_highlight_listing_keeps_polish_letters():
    text = "TITLE Wykres prędkości kątowej\n"
    assert "prędkości kątowej" in highlight_listing(text, "html")
    assert "prędkości kątowej" in highlight_listing(text, "latex")


def test_highlight_listing_without_pygments(monkeypatch):
    import amilpy.output.highlight as hl

    monkeypatch.setattr(hl, "AmilLexer", None)
    text = "X = A & \n  *B\n"
    assert hl.highlight_listing(text) == text
    assert hl.highlight_listing(text, "html") == (
        '<div class="highlight"><pre>X = A &amp; \n  *B\n</pre></div>\n')
    # (the one Verbatim writer of the LaTeX report: a listing's \\ { } as characters)
    assert hl.highlight_listing(text + "{\\end}\n", "latex") == (
        "\\begin{Verbatim}[commandchars=\\\\\\{\\},fontsize=\\small]\n" + text
        + "\\char123{}\\char92{}end\\char125{}\n\\end{Verbatim}\n")
    assert hl.style_defs("html") == ""


def test_unknown_formatter():
    with pytest.raises(ValueError, match="formatter"):
        highlight_listing("X = 1\n", "rtf")


# ------------------------------------------------------------- TextMate grammar

# Oniguruma constructs Python's `re` does not read: \G, \h, \H, possessive
# quantifiers, named groups without P, absent operator, \p{...}, \k<...>.
_ONIG_ONLY = re.compile(r"\\[GhHzKRXyY]|\\p\{|\\k<|\(\?<[A-Za-z]|\(\?~|[*+?}]\+")


def _regexes(node, where="grammar"):
    if isinstance(node, dict):
        for key, value in node.items():
            if key in ("match", "begin", "end", "while") and isinstance(value, str):
                yield f"{where}.{key}", value
            else:
                yield from _regexes(value, f"{where}.{key}")
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _regexes(value, f"{where}[{i}]")


def test_vscode_extension_files_are_valid_json():
    package = json.loads((EDITOR / "package.json").read_text(encoding="utf-8"))
    json.loads((EDITOR / "language-configuration.json").read_text(encoding="utf-8"))
    grammar = json.loads(TMGRAMMAR.read_text(encoding="utf-8"))
    assert grammar["scopeName"] == "source.amil"
    contributed = package["contributes"]["grammars"][0]
    assert contributed["scopeName"] == "source.amil"
    assert (EDITOR / contributed["path"]).resolve() == TMGRAMMAR.resolve()
    assert package["contributes"]["languages"][0]["extensions"] == [".amil", ".csl", ".fst"]


def test_textmate_regexes_compile():
    grammar = json.loads(TMGRAMMAR.read_text(encoding="utf-8"))
    found = list(_regexes(grammar))
    assert len(found) > 10
    checked = 0
    for where, pattern in found:
        if _ONIG_ONLY.search(pattern):
            continue
        try:
            re.compile(pattern)
        except re.error as exc:  # pragma: no cover - the message is the point
            pytest.fail(f"{where}: {pattern!r}: {exc}")
        checked += 1
    assert checked > 10


def test_textmate_includes_resolve():
    grammar = json.loads(TMGRAMMAR.read_text(encoding="utf-8"))
    text = TMGRAMMAR.read_text(encoding="utf-8")
    for name in re.findall(r'"include": "#([^"]+)"', text):
        assert name in grammar["repository"], name


def test_textmate_scopes_and_names_match_the_lexer():
    grammar = json.loads(TMGRAMMAR.read_text(encoding="utf-8"))
    text = TMGRAMMAR.read_text(encoding="utf-8")
    for scope in ("comment.line", "keyword.control", "support.function", "constant.language",
                  "constant.numeric", "keyword.operator", "string.unquoted", "variable.other",
                  "punctuation.separator.continuation"):
        assert f'"{scope}.' in text, scope
    repo = grammar["repository"]

    def listed(pattern: str) -> set[str]:
        inner = re.search(r"\(\?i:([A-Z0-9_|]+)\)", pattern).group(1)
        return set(inner.split("|"))

    assert listed(repo["functions"]["match"]) == set(BUILTIN_FUNCTIONS)
    assert listed(repo["reserved"]["match"]) == set(RESERVED_NAMES)
    keywords = set().union(*(listed(p["match"]) for p in repo["keywords"]["patterns"]))
    assert keywords | {"TITLE", "LABEL"} == set(KEYWORDS)


def test_textmate_lines_behave_like_the_lexer():
    """The single-line rules, run with Python's `re`, agree with the lexer."""
    repo = json.loads(TMGRAMMAR.read_text(encoding="utf-8"))["repository"]
    flags = re.MULTILINE
    assert re.match(repo["comment-line"]["match"], "   * note", flags)
    assert not re.match(repo["comment-line"]["match"], "X = A*B", flags)
    number = repo["numbers"]["match"]
    for literal in ("12", "12.", ".5", "1.5E-3", "1.5e+3", "1.5D-3"):
        assert re.fullmatch(number, literal), literal
    assert re.match(number, "12...").group(0) == "12"
    title = re.match(repo["title"]["match"], "title Napęd dwumasowy ! c", flags)
    assert title.group(1) == "title" and title.group(3) == "Napęd dwumasowy "
    title = re.match(repo["title"]["match"], "TITLE A ... ", flags)
    assert title.group(3) == "A"
    assert re.match(repo["continuation"]["begin"], "... ! more\n")
    assert re.match(repo["functions"]["match"], "intgrl (")
    assert not re.match(repo["functions"]["match"], "INTGRL = 1")
