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
and must be given a value before it is read. Only the subroutines a CALL names are
read: notes, data and other routines after STOP are left as they are. What the subset
does not run in a called subroutine -- INTEGER
and the names Fortran types as integers by default (I to N, with no IMPLICIT REAL),
arrays, DO, GO TO and labels, SAVE, DATA, PARAMETER, COMMON, FUNCTION, a CALL inside a
subroutine, a RETURN before the end -- is refused at its line and column, by name, and
so are the CALLs whose Fortran meaning a PROCEDURAL cannot have: a name given both as a
value the routine reads and as an argument it assigns, one given to two assigned
arguments, an assigned argument some path leaves as it was.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..diagnostics import Diagnostic, Span
from . import syntax as ast
from .lexical import code_end

# statements of the subset read here (the rest are read by the listing's grammar)
_SUBROUTINE = re.compile(r"SUBROUTINE\s+([A-Za-z]\w*)\s*(?:\(\s*([^)]*)\))?\s*$", re.I)
_HEAD = re.compile(r"SUBROUTINE\s+[A-Za-z]\w*\s*(?:\(|$)", re.I)
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


def read_subroutines(lines: list[str], first: int, path: str | None,
                     errors: list[Diagnostic], parser, called: set[str]
                     ) -> dict[str, Subroutine | None]:
    """The subroutines `called` in lines[first:] (0-based; diagnostics count lines from
    1); None for one whose faults are said (its CALLs add nothing to them). The other
    text after STOP (notes, data, routines nothing calls) is not read. `parser`: the
    listing's own (the statements of a body are read by its grammar)."""
    units: dict[str, Subroutine | None] = {}
    for unit in _units(_statements(lines, first), errors):
        name = _SUBROUTINE.match(unit[0][2]).group(1).upper()
        if name not in called:
            continue
        if name in units:
            errors.append(Diagnostic(f"SUBROUTINE {name} is written twice",
                                     Span(unit[0][0] + 1, unit[0][1] + 1),
                                     "a subroutine has one definition"))
            continue
        units[name] = _read_unit(unit, len(lines), path, errors, parser)
    return units


def _statements(lines: list[str], first: int) -> list[tuple[int, int, str, str]]:
    """(line index, column of the code, code, label) of each statement of the
    SUBROUTINE ... END units, fixed form: columns 7 to 72, continuation lines joined to
    the statement they continue; the lines outside the units are not read."""
    out: list[list] = []
    inside = False
    for k in range(first, len(lines)):
        line = lines[k].rstrip("\n").expandtabs(6)[:72]
        if not line.strip() or line[:1] in "Cc*!":
            continue
        code = line[6:] if len(line) > 6 else ""
        code = code[:code_end(code)]
        if inside and len(line) > 5 and line[5] not in " 0" and out:
            out[-1][2] += " " + code.strip()
            continue
        if not inside:
            # (the head's arguments may go on in continuation lines)
            if not _HEAD.match(code.strip()) or line[:6].strip():
                continue
            inside = True
        label = line[:5].strip()
        if not code.strip() and not label:
            continue
        out.append([k, 6 + len(code) - len(code.lstrip()), code.strip(), label])
        if _END.match(code.strip()) and not label:
            inside = False
    return [(k, col, code, label) for k, col, code, label in out]


def _units(statements, errors: list[Diagnostic]):
    """The statements of each SUBROUTINE ... END."""
    unit: list | None = None
    for st in statements:
        code = st[2]
        if unit is None:
            if _SUBROUTINE.match(code):
                unit = [st]
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
    real_all, declared, bad, none = False, set(), False, False
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
            elif what == "NONE":
                none = True
            else:
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
        found = next(((m, what) for p, what in _REFUSED if (m := p.match(code))), None)
        if found is not None or real:  # (a REAL declaration here declares an array)
            match, what = found or (None, "arrays in a subroutine")
            word = (match.group(1) or "").upper() if match is not None and match.groups() \
                else ""
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
    text = ["" for _ in range(n_lines)]
    text[k0] = "PROGRAM " + name  # (where the SUBROUTINE line is: every line in its place)
    for k, col, code in executable:
        text[k] = " " * col + code
    text[unit[-1][0]] = "END"
    source = "\n".join(text) + "\n"
    from lark.exceptions import UnexpectedInput

    from .errors import syntax_diagnostic
    from .lexical import prepare

    try:
        tree = parser.parse(prepare(source))
    except UnexpectedInput as exc:
        errors.append(syntax_diagnostic(exc, prepare(source), parser))
        return None
    builder = Builder(source, path)
    builder.acsl = True
    items = builder.statements(tree)
    _, _, statements = Nester(builder.errors).nest(items)
    errors.extend(builder.errors)
    if builder.errors:
        return None
    for st in statements:
        if not isinstance(st, (ast.Assign, ast.If)):
            errors.append(Diagnostic(
                f"this statement in SUBROUTINE {name}: not supported", st.span,
                "the subroutines after STOP run assignments and IFs"))
            return None
    body_nodes = tuple(statements)
    if not real_all:
        for node in (n for st in body_nodes for n in ast.walk(st)):
            names = [node.name] if isinstance(node, ast.Name) else \
                list(node.targets) if isinstance(node, ast.Assign) else []
            for n in names:
                if n in declared:
                    continue
                if none:  # (IMPLICIT NONE: every name is declared)
                    errors.append(Diagnostic(
                        f"{n} is not declared (IMPLICIT NONE in SUBROUTINE {name})",
                        node.span, f"declare it: REAL {n}"))
                    return None
                if n[:1] in "IJKLMN":
                    errors.append(Diagnostic(
                        f"{n} is an INTEGER by Fortran's implicit typing (SUBROUTINE {name}): "
                        "integer arithmetic is not supported", node.span,
                        "write IMPLICIT REAL (A-Z), or declare it REAL"))
                    return None
    return Subroutine(name, params, body_nodes, span)


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
        reads, everywhere = _flow(sub.body)
        counts[st.name] = k = counts.get(st.name, 0) + 1
        names: dict[str, str] = {}
        values: dict[str, ast.Node] = {}
        outputs: list[str] = []
        inputs: list[str] = []
        for p, actual in zip(sub.params, st.args, strict=True):
            if p in assigned:
                fault = None
                if not isinstance(actual, ast.Name):
                    fault = (f"argument {p} of SUBROUTINE {st.name} is assigned in it: the "
                             "CALL must give a name there", f"pass a variable as {p}")
                elif p in reads:
                    fault = (f"argument {p} of SUBROUTINE {st.name} is read before it is "
                             "assigned (an input and an output at once): not supported",
                             "pass its value in an argument of its own")
                elif p not in everywhere:
                    fault = (f"argument {p} of SUBROUTINE {st.name} is not assigned on every "
                             "path through it (where it is not, Fortran keeps its value "
                             "from before the CALL): not supported",
                             f"give {p} a value on every path, first thing in the routine")
                elif actual.name in outputs:
                    fault = (f"the CALL gives {actual.name} to two arguments SUBROUTINE "
                             f"{st.name} assigns", "give each its own variable")
                if fault is not None:
                    errors.append(Diagnostic(fault[0], st.span, fault[1]))
                    return []
                names[p] = actual.name
                outputs.append(actual.name)
            else:
                values[p] = actual
                inputs.extend(n.name for n in ast.walk(actual) if isinstance(n, ast.Name))
        both = sorted(set(outputs) & set(inputs))
        if both:
            errors.append(Diagnostic(
                f"the CALL gives {both[0]} to SUBROUTINE {st.name} both as a value it reads "
                "and as an argument it assigns: not supported", st.span,
                "pass the value in a variable of its own"))
            return []
        params = set(sub.params)
        unknown = sorted((n, span) for n, span in reads.items() if n not in params)
        if unknown:
            n, span = unknown[0]
            errors.append(Diagnostic(
                f"{n} is read in SUBROUTINE {st.name} before it has a value (its names are "
                "its own)", span, f"pass {n} as an argument, or give it a value before"))
            return []
        local = {n: f"{st.name}#{k}.{n}" for n in assigned - params}
        names |= local
        body = tuple(_rename(s, names, values) for s in sub.body)
        # (the routine's own names are outputs too: each call's, shown as NAME#k.X)
        return [ast.Procedural(tuple(dict.fromkeys(outputs + sorted(local.values()))),
                               tuple(dict.fromkeys(inputs)), body, st.span)]

    return [x for st in statements for x in one(st)]


def _flow(body) -> tuple[dict[str, object], set[str]]:
    """The names read where no assignment before them (in written order, on every
    path) has given them a value, with where the first such read is; and the names
    every path through the body assigns."""
    reads: dict[str, object] = {}

    def read(expr, given: set[str]) -> None:
        for n in ast.walk(expr):
            if isinstance(n, ast.Name) and n.name not in given:
                reads.setdefault(n.name, n.span)

    def walk(statements, given: set[str]) -> set[str]:
        given = set(given)
        for st in statements:
            if isinstance(st, ast.Assign):
                for e in (st.expr, *st.subscripts):
                    read(e, given)
                given.update(st.targets)
            elif isinstance(st, ast.If):
                branch_given = []
                for b in st.branches:
                    if b.cond is not None:
                        read(b.cond, given)
                    branch_given.append(walk(b.body, given))
                if st.branches[-1].cond is None:  # (an ELSE: every path passes a branch)
                    given |= set.intersection(*branch_given)
        return given

    everywhere = walk(body, set())
    return reads, everywhere
