"""The Fortran subroutines written after an FST listing's STOP, and the CALLs that run
them: a first subset of Fortran 77 (issue 23), read into the listing's own syntax
and never handed to a compiler or to Python as text.

    CALL GLA(TIME, DOYEM, DTEFF, ..., GLAI)       in the listing's sorted code, runs
                                                  SUBROUTINE GLA(TIME, ..., GLAI) as a
                                                  PROCEDURAL: its outputs the actual
                                                  arguments the body assigns, its
                                                  inputs the names the others read

The subset: fixed-form source (a `C`, `c`, `*` or `!` in column 1 comments a line, a
mark in column 6 continues one), `SUBROUTINE NAME(A1, ...)` ... `END`, `IMPLICIT REAL
(A-Z)` or `IMPLICIT NONE` with `REAL` declarations of scalars, assignments, the logical
IF `IF (c) statement`, block IFs with ELSE IF and ELSE, intrinsics as the listing has
them, and `RETURN` as the last statement. An argument the body assigns is an output
(the call must give a name there); one it only reads is an input and stands for the
call's expression; every other name is the subroutine's own (each call's, `NAME#k.X`),
and must be given a value before it is read. What the subset does not run -- INTEGER
and the names Fortran types as integers by default (I to N, with no IMPLICIT REAL),
arrays, DO, GO TO and labels, SAVE, DATA, PARAMETER, COMMON, FUNCTION, a CALL inside a
subroutine, a RETURN before the end -- is refused at its line and column, by name.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

from ..diagnostics import Diagnostic, Span
from . import syntax as ast

# statements of the subset read here (the rest are read by the listing's grammar)
_SUBROUTINE = re.compile(r"SUBROUTINE\s+([A-Za-z]\w*)\s*(?:\(\s*([^)]*)\))?\s*$", re.I)
_END = re.compile(r"END(?:\s*SUBROUTINE(?:\s+\w+)?)?\s*$", re.I)
_IMPLICIT = re.compile(r"IMPLICIT\s+(.*)$", re.I)
_REAL = re.compile(r"(?:REAL(?:\*\d+)?|DOUBLE\s*PRECISION)\s+(.*)$", re.I)
_RETURN = re.compile(r"RETURN\s*$", re.I)
# refused by name: (pattern, the construct as a reader knows it)
_REFUSED = [
    (re.compile(r"(INTEGER|LOGICAL|CHARACTER)\b", re.I), "{0} variables in a subroutine"),
    (re.compile(r"DO\b\s*(\d+\s*,?\s*)?[A-Za-z]\w*\s*=", re.I), "DO loops in a subroutine"),
    (re.compile(r"GO\s*TO\b", re.I), "GO TO"),
    (re.compile(r"(SAVE|DATA|PARAMETER|COMMON|EQUIVALENCE|EXTERNAL|DIMENSION|CALL|"
                r"FUNCTION|ENTRY|READ|WRITE|FORMAT|OPEN|CLOSE|STOP)\b", re.I),
     "Fortran's {0} in a subroutine"),
]


@dataclass(frozen=True)
class Subroutine:
    name: str
    params: tuple[str, ...]
    body: tuple  # the listing's statements (Assign, If)
    span: Span
    last_line: int


def after_stop(lines: list[str], stop_at) -> int | None:
    """The index of the first line after the STOP (or ENDJOB) statement line, None if
    there is none. `stop_at(line) -> bool` says which line that is (the reader's rule)."""
    for k, line in enumerate(lines):
        if stop_at(line):
            return k + 1
    return None


def read_subroutines(lines: list[str], first: int, path: str | None,
                     errors: list[Diagnostic], parser) -> dict[str, Subroutine | None]:
    """The subroutines in lines[first:] (0-based; diagnostics count lines from 1); None
    for one whose faults are said (its CALLs add nothing to them). `parser`: the
    listing's own (the statements of a body are read by its grammar)."""
    units: dict[str, Subroutine | None] = {}
    for unit in _units(_statements(lines, first), errors):
        sub = _read_unit(unit, len(lines), path, errors, parser)
        if sub is None:
            units.setdefault(_SUBROUTINE.match(unit[0][2]).group(1).upper(), None)
            continue
        if sub.name in units:
            errors.append(Diagnostic(f"SUBROUTINE {sub.name} is written twice", sub.span,
                                     "a subroutine has one definition"))
            continue
        units[sub.name] = sub
    return units


def _statements(lines: list[str], first: int) -> list[tuple[int, int, str]]:
    """(line index, column of the code, code) of each statement, fixed form:
    continuation lines joined to the statement they continue."""
    out: list[list] = []
    for k in range(first, len(lines)):
        line = lines[k].rstrip("\n").expandtabs(6)
        if not line.strip() or line[:1] in "Cc*!":
            continue
        code = line[6:] if len(line) > 6 else ""
        bang = _bang(code)
        code = code[:bang]
        if len(line) > 5 and line[5] not in " 0" and out:
            out[-1][2] += " " + code.strip()
            continue
        label = line[:5].strip()
        if not code.strip() and not label:
            continue
        out.append([k, 6 + len(code) - len(code.lstrip()), code.strip(), label])
    return [(k, col, code, label) for k, col, code, label in out]


def _bang(code: str) -> int:
    quoted = False
    for i, ch in enumerate(code):
        if ch == "'":
            quoted = not quoted
        elif ch == "!" and not quoted:
            return i
    return len(code)


def _units(statements, errors: list[Diagnostic]):
    """The statements of each SUBROUTINE ... END."""
    unit: list | None = None
    for st in statements:
        k, col, code, _ = st
        if unit is None:
            if _SUBROUTINE.match(code):
                unit = [st]
            elif re.match(r"(?:REAL\s+|INTEGER\s+|LOGICAL\s+|DOUBLE\s*PRECISION\s+)?"
                          r"FUNCTION\b", code, re.I):
                errors.append(Diagnostic(
                    "a Fortran FUNCTION after STOP: not supported", Span(k + 1, col + 1),
                    "write it as a SUBROUTINE with the value as its last argument"))
                return
            continue
        unit.append(st)
        if _END.match(code):
            yield unit
            unit = None
    if unit is not None:
        k, col, code, _ = unit[0]
        errors.append(Diagnostic("SUBROUTINE is never ended", Span(k + 1, col + 1),
                                 "end it with END"))


def _read_unit(unit, n_lines: int, path: str | None, errors: list[Diagnostic], parser
               ) -> Subroutine | None:
    from .blocks import Nester
    from .build import Builder

    k0, col0, code0, _ = unit[0]
    head = _SUBROUTINE.match(code0)
    name = head.group(1).upper()
    span = Span(k0 + 1, col0 + 1, k0 + 1, col0 + 1 + len(code0))
    params = tuple(p.strip().upper() for p in (head.group(2) or "").split(",") if p.strip())
    body = unit[1:-1]
    real_all, declared, bad = False, set(), False
    executable: list = []
    for i, (k, col, code, label) in enumerate(body):
        where = Span(k + 1, col + 1, k + 1, col + 1 + len(code))
        if label:
            errors.append(Diagnostic(f"the statement label {label} (in SUBROUTINE {name}): "
                                     "not supported", where, "write IF ... END IF"))
            bad = True
            continue
        implicit = _IMPLICIT.match(code)
        if implicit:
            what = implicit.group(1).replace(" ", "").upper()
            if what == "REAL(A-Z)":
                real_all = True
            elif what != "NONE":
                errors.append(Diagnostic(f"IMPLICIT {implicit.group(1)}: not supported", where,
                                         "write IMPLICIT REAL (A-Z)"))
                bad = True
            continue
        real = _REAL.match(code)
        if real and "(" not in real.group(1):
            declared.update(n.strip().upper() for n in real.group(1).split(","))
            continue
        if _RETURN.match(code):
            if any(not _RETURN.match(c) for _, _, c, _ in body[i + 1:]):
                errors.append(Diagnostic(
                    f"RETURN before the end of SUBROUTINE {name}: not supported", where,
                    "write the statements after it in the ELSE of an IF"))
                bad = True
            continue
        refused = next(((p, what) for p, what in _REFUSED if p.match(code)), None)
        if refused is not None or real:
            pattern, what = refused or (None, "arrays in a subroutine")
            word = pattern.match(code).group(1).upper() if pattern is not None and \
                pattern.match(code).groups() and pattern.match(code).group(1) else ""
            errors.append(Diagnostic(f"{what.format(word)} (SUBROUTINE {name}, line {k + 1}): "
                                     "not supported", where,
                                     "the subroutines after STOP run assignments and IFs "
                                     "(issue 23's first subset)"))
            bad = True
            continue
        executable.append((k, col, code))
    if bad:
        return None
    # the executable statements read by the listing's own grammar (ACSL form: IF blocks,
    # .LT. and the rest), each at its own line and column
    text = ["" for _ in range(n_lines + 2)]
    text[0] = "PROGRAM " + name
    for k, col, code in executable:
        text[k + 1] = " " * col + code
    text[n_lines + 1] = "END"
    source = "\n".join(text) + "\n"
    from lark.exceptions import UnexpectedInput

    from .errors import syntax_diagnostic
    from .lexical import prepare

    try:
        tree = parser.parse(prepare(source))
    except UnexpectedInput as exc:
        d = syntax_diagnostic(exc, prepare(source), parser)
        errors.append(replace(d, span=Span(d.span.line - 1, d.span.column, d.span.end_line - 1,
                                           d.span.end_column) if d.span else None))
        return None
    builder = Builder(source, path)
    builder.acsl = True
    items = builder.statements(tree)
    _, _, statements = Nester(builder.errors).nest(items)
    shifted = [_shift(d) for d in builder.errors]
    errors.extend(shifted)
    if shifted:
        return None
    for st in statements:
        if not isinstance(st, (ast.Assign, ast.If)):
            errors.append(Diagnostic(
                f"{type(st).__name__.upper()} in SUBROUTINE {name}: not supported",
                _line_down(st.span), "the subroutines after STOP run assignments and IFs"))
            return None
    body_nodes = tuple(_lines_down(st) for st in statements)
    if not real_all:
        for node in (n for st in body_nodes for n in ast.walk(st)):
            names = [node.name] if isinstance(node, ast.Name) else \
                list(node.targets) if isinstance(node, ast.Assign) else []
            for n in names:
                if n[:1] in "IJKLMN" and n not in declared:
                    errors.append(Diagnostic(
                        f"{n} is an INTEGER by Fortran's implicit typing (SUBROUTINE {name}): "
                        "integer arithmetic is not supported", node.span,
                        "write IMPLICIT REAL (A-Z), or declare it REAL"))
                    return None
    last = unit[-1][0] + 1
    return Subroutine(name, params, body_nodes, span, last)


def _shift(d: Diagnostic) -> Diagnostic:
    return replace(d, span=_line_down(d.span)) if d.span is not None else d


def _line_down(span: Span | None) -> Span | None:
    # (the synthetic text puts line k of the file at line k + 1)
    if span is None:
        return None
    return Span(span.line - 1, span.column, span.end_line - 1, span.end_column)


def _lines_down(node):
    """node, and every node under it, with spans one line up (see `_line_down`)."""
    changes = {}
    for field in getattr(node, "__dataclass_fields__", {}):
        value = getattr(node, field)
        if isinstance(value, Span):
            changes[field] = _line_down(value)
        elif isinstance(value, ast.Node):
            changes[field] = _lines_down(value)
        elif isinstance(value, tuple) and value and isinstance(value[0], (ast.Node, Span)):
            changes[field] = tuple(_line_down(v) if isinstance(v, Span) else _lines_down(v)
                                   for v in value)
    return replace(node, **changes) if changes else node


def expand_calls(statements: list, subroutines: dict[str, Subroutine | None],
                 errors: list[Diagnostic]) -> list:
    """The statements with each CALL of a subroutine written out as a PROCEDURAL."""
    from .macros import _assigned, _rename, _with_bodies

    counts: dict[str, int] = {}

    def one(st):
        if not isinstance(st, ast.SubroutineCall):
            return [_with_bodies(st, lambda body: [x for s in body for x in one(s)])]
        if st.name in subroutines and subroutines[st.name] is None:
            return []  # (its faults are said at the subroutine)
        sub = subroutines.get(st.name)
        if sub is None:
            errors.append(Diagnostic(
                f"CALL {st.name} (line {st.span.line}): no SUBROUTINE {st.name} follows STOP",
                st.span, f"write SUBROUTINE {st.name}(...) ... END after STOP, or rewrite it "
                "as statements or a PROCEDURE"))
            return []
        if len(st.args) != len(sub.params):
            errors.append(Diagnostic(
                f"CALL {st.name} gives {len(st.args)} argument(s); SUBROUTINE {st.name} "
                f"(line {sub.span.line}) takes {len(sub.params)}", st.span,
                f"write CALL {st.name}({', '.join(sub.params)})"))
            return []
        assigned = _assigned(sub.body)
        reads = _read_before_assigned(sub.body)
        counts[st.name] = k = counts.get(st.name, 0) + 1
        names: dict[str, str] = {}
        values: dict[str, ast.Node] = {}
        outputs: list[str] = []
        inputs: list[str] = []
        for p, actual in zip(sub.params, st.args, strict=True):
            if p in assigned:
                if not isinstance(actual, ast.Name):
                    errors.append(Diagnostic(
                        f"argument {p} of SUBROUTINE {st.name} is assigned in it: the CALL "
                        "must give a name there", st.span, f"pass a variable as {p}"))
                    return []
                if p in reads:
                    errors.append(Diagnostic(
                        f"argument {p} of SUBROUTINE {st.name} is read before it is assigned "
                        "(an input and an output at once): not supported", st.span,
                        "pass its value in an argument of its own"))
                    return []
                names[p] = actual.name
                outputs.append(actual.name)
            else:
                values[p] = actual
                inputs.extend(n.name for n in ast.walk(actual) if isinstance(n, ast.Name))
        params = set(sub.params)
        for n in sorted(reads - params):
            errors.append(Diagnostic(
                f"{n} is read in SUBROUTINE {st.name} before it has a value (its names are "
                "its own)", sub.span, f"pass {n} as an argument"))
            return []
        names |= {n: f"{st.name}#{k}.{n}" for n in assigned - params}
        body = tuple(_rename(s, names, values) for s in sub.body)
        return [ast.Procedural(tuple(dict.fromkeys(outputs)), tuple(dict.fromkeys(inputs)),
                               body, st.span)]

    return [x for st in statements for x in one(st)]


def _read_before_assigned(body) -> set[str]:
    """Names read where no assignment before them (in written order, on every path)
    has given them a value."""
    out: set[str] = set()

    def walk(statements, given: set[str]) -> set[str]:
        given = set(given)
        for st in statements:
            if isinstance(st, ast.Assign):
                out.update(n.name for e in (st.expr, *st.subscripts) for n in ast.walk(e)
                           if isinstance(n, ast.Name) and n.name not in given)
                given.update(st.targets)
            elif isinstance(st, ast.If):
                branch_given = []
                for b in st.branches:
                    if b.cond is not None:
                        out.update(n.name for n in ast.walk(b.cond)
                                   if isinstance(n, ast.Name) and n.name not in given)
                    branch_given.append(walk(b.body, given))
                if st.branches[-1].cond is None:  # (an ELSE: every path passes a branch)
                    given |= set.intersection(*branch_given)
        return given

    walk(body, set())
    return out
