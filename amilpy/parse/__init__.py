"""Source text -> abstract syntax (`syntax.Program`).

The only package that sees lark: the grammar is `grammar/amil.lark` (shipped as
`amilpy.grammar`), the parser is LALR with lark's cache so a start does not
rebuild the tables, and the tree is made by callbacks of our own as rules reduce
(`tree.read`: lark's tree builder with its positions was half of the parsing). A
syntax fault does not end the reading: the statement it
stands in is skipped and the text after it is read on, so every fault of the
file is reported at once (up to `MAX_ERRORS`).
"""

from __future__ import annotations

from functools import lru_cache
from importlib import resources

from ..diagnostics import AmilError, Diagnostic, Span
from ..language import ACSL_HEADS, split_lines
from . import arrays, texts
from . import syntax as ast
from .blocks import Nester
from .build import Builder
from .errors import syntax_diagnostic
from .jumps import lower_jumps
from .lexical import blank_comment_lines, code_end, continues, prepare
from .macros import expand, in_macros
from .syntax import MAX_DEPTH, no_collection
from .tree import read

__all__ = ["MAX_DEPTH", "MAX_ERRORS", "blank_comment_lines", "parse"]

MAX_ERRORS = 20  # syntax faults reported from one file


@lru_cache(maxsize=1)
def _parser():
    from lark import Lark

    grammar = resources.files("amilpy.grammar").joinpath("amil.lark").read_text("utf-8")
    return Lark(
        grammar,
        parser="lalr",
        lexer="contextual",
        propagate_positions=False,
        maybe_placeholders=True,
        cache=True,
    )


_continues = continues


@no_collection()
def parse(text: str, path: str | None = None) -> ast.Program:
    """Parse a listing. Raises `AmilError` with every syntax fault located."""
    from lark.exceptions import UnexpectedInput

    if text.startswith("\ufeff"):
        text = text[1:]
    # (NULs and ^Z after the last line: an old editor's padding or DOS end-of-file
    # mark, which the translators that read these files stopped at)
    text = text.rstrip("\x00\x1a")
    # one definition of a line (language.split_lines), for the reader and messages
    prepared = prepare("\n".join(split_lines(text)))
    if not prepared.endswith("\n"):
        prepared += "\n"
    parser = _parser()
    lines = prepared.split("\n")
    errors: list[Diagnostic] = []
    offset = 0  # lines of the file before the part being read
    tree = None
    while True:
        part = prepared if offset == 0 else "\n".join(lines[offset:])
        try:
            tree = read(parser, part)
        except UnexpectedInput as exc:
            errors.append(_diagnose(exc, part, lines, offset, parser))
            resume = _after_statement(lines, offset, getattr(exc, "line", None))
            if len(errors) >= MAX_ERRORS or resume is None:
                if resume is not None:
                    errors.append(Diagnostic(
                        f"stopped reading after {MAX_ERRORS} syntax errors", None,
                        "fix these and run again", severity="note"))
                break
            offset = resume
            continue
        break
    if errors:
        raise AmilError(errors, path, text)
    builder = Builder(text, path, _parser())
    builder.acsl = is_acsl(prepared)
    items = builder.statements(tree)
    nester = Nester(builder.errors)
    form, name, statements = nester.nest(items)
    statements, macros = expand(statements, builder.errors, form == "ACSL")
    statements = lower_jumps(statements, builder.errors, sorted_top=form == "ACSL")
    statements = _subroutines_called(statements, text, path, builder.errors, builder.calls)
    own_pi = _own_pi(statements, form == "ACSL")
    statements = texts.set_aside(statements, builder.errors)
    statements, fixed = arrays.expand(statements, builder.errors, form == "ACSL",
                                      nester.notes, "[" in text)
    if builder.errors:
        raise AmilError(in_macros(sorted(builder.errors, key=_where), macros), path, text)
    return ast.Program(tuple(statements), path, text, form, name, macros, fixed,
                       tuple(nester.notes), own_pi)


_FST_STATEMENTS = (ast.Translation, ast.Weather, ast.DefineCall, ast.Event, ast.SetValue)


def _own_pi(statements: list, acsl: bool) -> bool:
    """Whether an FST listing (one with FST's own statements: TRANSLATION_GENERAL,
    WEATHER, DEFINE_CALL, EVENT, SET) or an ACSL program assigns PI: neither language
    has a PI of its own; LINGRA computes with its PI = 3.1416, not pi, and the EPA
    lead model with its CONSTANT PI = 3.141592."""
    everything = ast.every_statement(statements)
    return (acsl or any(isinstance(st, _FST_STATEMENTS) for st in everything)) and any(
        (isinstance(st, ast.Assign) and "PI" in st.targets) or
        (isinstance(st, ast.Procedural) and "PI" in st.outputs) or  # (a CALL's)
        (isinstance(st, ast.Data) and any(it.name == "PI" for it in st.items))
        for st in everything)


def _subroutines_called(statements: list, text: str, path: str | None,
                        errors: list[Diagnostic], calls: bool = True) -> list:
    """CALLs of the subroutines written after STOP, and references to the FUNCTIONs
    written there, written out (parse/fortran.py); the statements as they are when
    there is neither. `calls`: a CALL statement may be among them (False: the
    builder made none, and without a STOP nothing else is looked for)."""
    from . import fortran
    from .lexical import stop_line

    if not calls and stop_line(blank_comment_lines("\n".join(split_lines(text)))
                               .split("\n")) is None:
        return statements  # (the walk below, 5 % of reading a large listing, saved)
    called: set[str] = set()
    named: set[str] = set()  # (the functions called: a FUNCTION's references among them)
    for n in (n for st in statements for n in ast.walk(st)):
        if isinstance(n, ast.SubroutineCall):
            called.add(n.name)
        elif isinstance(n, ast.Call):
            named.add(n.func)
    if not called and not named:
        return statements
    lines = split_lines(text)
    stop = stop_line(blank_comment_lines("\n".join(lines)).split("\n"))
    if stop is None:
        return statements if not called else fortran.expand_calls(statements, {}, errors)
    called |= named & fortran.function_names(lines, stop + 1)
    if not called:
        return statements
    subroutines = fortran.read_subroutines(lines, stop + 1, path, errors, _parser(), called)
    return fortran.expand_calls(statements, subroutines, errors)


def is_acsl(prepared: str) -> bool:
    """The file is in ACSL form: its first statement is PROGRAM or MODEL, or the first
    after the ACSL MACROs (MACRO NAME(A1, ...) ... MACRO END) defined before it."""
    import re

    in_macro = False
    for line in prepared.split("\n"):
        code = line[:code_end(line)].strip()
        if not code:
            continue
        if in_macro:
            in_macro = re.fullmatch(r"(?i)MACRO\s+END(MACRO)?", code) is None
            continue
        if re.match(r"(?i)MACRO\s+[A-Za-z]\w*\s*\(", code):
            in_macro = True  # (CSMP III's MACRO O = NAME(P) has '=' before its '(')
            continue
        word = re.match(r"[A-Za-z]+", code)
        return word is not None and word.group().upper() in ACSL_HEADS
    return False


def _where(d: Diagnostic) -> tuple[int, int]:
    return (d.span.line, d.span.column) if d.span else (10**9, 0)


def _diagnose(exc, part: str, lines: list[str], offset: int, parser) -> Diagnostic:
    """The diagnostic of a fault, found again in its statement read alone: the
    friendly labels are matched against a statement at the start of a file."""
    from lark.exceptions import UnexpectedInput

    line = getattr(exc, "line", None)
    if isinstance(line, int) and 1 <= line and offset + line - 1 < len(lines):
        first = last = offset + line - 1
        while first > offset and _continues(lines[first - 1]):
            first -= 1
        while last + 1 < len(lines) and _continues(lines[last]):
            last += 1
        alone = "\n".join(lines[first:last + 1]) + "\n"
        try:
            parser.parse(alone)
        except UnexpectedInput as again:
            if getattr(again, "line", None) == line - (first - offset):
                return _shifted(syntax_diagnostic(again, alone, parser), first)
    return _shifted(syntax_diagnostic(exc, part, parser), offset)


def _after_statement(lines: list[str], offset: int, line: int | None) -> int | None:
    """The index of the first line after the statement holding line `line` of the
    part that starts at `offset` (None: nothing left to read)."""
    if not isinstance(line, int) or line < 1:
        return None
    k = offset + line - 1
    while k < len(lines) and _continues(lines[k]):
        k += 1
    k += 1
    return k if k < len(lines) and any(s.strip() for s in lines[k:]) else None


def _shifted(d: Diagnostic, lines: int) -> Diagnostic:
    """A diagnostic found in a later part of the file, at its place in the file."""
    if d.span is None or lines == 0:
        return d
    s = d.span
    span = Span(s.line + lines, s.column, None if s.end_line is None else s.end_line + lines,
                s.end_column)
    return Diagnostic(d.message, span, d.hint, d.severity, d.related)
