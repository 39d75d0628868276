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
(A-Z)` or `IMPLICIT NONE`, `REAL`, `INTEGER`, `LOGICAL` (.TRUE. is 1, .FALSE. 0) and
`DIMENSION` declarations, the
routine's own arrays of one subscript (`REAL XG(3)`) and `DATA` for them, `PARAMETER`
(named constants), `SAVE` (below), assignments,
the logical IF `IF (c) statement`, the arithmetic IF `IF (e) 10, 20, 30` (forward, as
GO TO's), block IFs with ELSE IF and ELSE, DO loops (`DO 10 I
= 1, 3` ... `10 CONTINUE`, or `DO I = 1, 3` ... `END DO`: the listing's own, written
out pass by pass), CALLs of the other routines after STOP (each written out in place),
FUNCTION subprograms (`REAL FUNCTION F(X)` ... `F = ...` ... `END`; a reference F(X) in
the listing or in a routine is written out as a CALL of F before the statement that
holds it, with F's value its last argument: `expand_functions`), GO TO forward with
its labels (written out as IF blocks, as the ACSL form's: parse/jumps.py), intrinsics
as the listing has them, `RETURN` as the last statement, and `STOP` or `STOP 'text'`
(the routine sets a flag where Fortran reaches it, and the listing's CALL stops the
run where the flag is set, saying the text; as Fortran's STOP ends the program, no
later run is made: `syntax.Termt.ends_job`), TTUTIL's `CALL
FATALERR(MODULE, MESSAGE)` (likewise, saying both) with `CHARACTER*20 M` texts given
once in quotes for it, and array
arguments (`REAL MNDAT(NH)`: the CALL gives the name of one of the listing's ARRAYs,
whose elements the body reads). An argument the body assigns is an output (the call
must give a name there); one it only reads is an input and stands for the call's
expression; every other name is the subroutine's own (each call's, `NAME#k.X`), and
must be given a value before it is read. Only the subroutines a CALL names, and those
they call, are read: notes, data and other routines after STOP are left as they are.

Fortran passes a variable itself: an argument the routine reads before it assigns it
(LINGRA's `INCUT = INCUT + 1.`), or assigns on some paths only, starts from the
variable's value before the CALL and gives it the new one. FSE's generated code keeps
every variable from one rate calculation to the next, so that value is the one the
routine left at the last step point (`library.KEPT`; a PARAM's own at first: the
listing's name is then the changed value everywhere, the PARAM `NAME#PARAM`, set from
outside as NAME), or, for a weather variable, the day's
(PENMAN's `VP = MIN(VP, SVP)`: `library.BEFORE`); the listing reads the new value.
A routine's own name that SAVE lists (or every one, under SAVE alone), or that DATA
gives a value the routine changes (a FIRST flag), is kept so too: read before the
routine assigns it, it is what this CALL left at the last step point (DATA's value at
first, else 0, as static storage starts). Each run (a rerun after END) starts them
afresh, as it starts its states; FSE reads its PARAMs again for a rerun but keeps
what a routine SAVEs from the run before (no published listing depends on that).

The listing computes in real numbers. Fortran's INTEGERs (declared, or by its implicit
typing I to N) give the same numbers while they hold whole numbers and are not divided
by one another: an INTEGER given any other value, or a division of two, is refused, as
are an array's DATA values the routine changes (Fortran keeps them from one CALL to the
next), and a name kept so in a routine another routine CALLs. Also
refused at its line and column, by name: a GO TO back or computed, a PARAMETER
assigned, COMMON, an array argument assigned, LOGICAL arrays, CHARACTER other than
FATALERR's texts,
recursion, a RETURN before the end; and the CALLs whose Fortran meaning a PROCEDURAL
cannot have: a name given both as a value the routine reads and as an argument it
assigns, one given to two assigned arguments, and an argument changed from its value
before in a
routine's CALL of another (where nothing keeps it).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from dataclasses import field as dataclass_field

from ..diagnostics import Diagnostic, Span
from ..library import BEFORE, KEPT
from . import syntax as ast
from .jumps import lower_jumps
from .lexical import code_end

# statements of the subset read here (the rest are read by the listing's grammar)
# a declaration's type, a FUNCTION's
_TYPE = r"REAL(?:\*\d+)?|DOUBLE\s*PRECISION|INTEGER(?:\*\d+)?|LOGICAL(?:\*\d+)?"
_SUBROUTINE = re.compile(r"SUBROUTINE\s+([A-Za-z]\w*)\s*(?:\(\s*([^)]*)\))?\s*$", re.I)
# a FUNCTION subprogram: its type (REAL, INTEGER, ... or none: Fortran's implicit
# typing of its name), its name and its arguments
_FUNCTION = re.compile(rf"(?:({_TYPE})\s+)?FUNCTION\s+([A-Za-z]\w*)\s*\(\s*([^)]*)\)\s*$",
                       re.I)
_HEAD = re.compile(rf"(?:(?:{_TYPE})\s+)?(?:SUBROUTINE|FUNCTION)\s+[A-Za-z]\w*\s*(?:\(|$)", re.I)
_END = re.compile(r"END(?:\s*(?:SUBROUTINE|FUNCTION)(?:\s+\w+)?)?\s*$", re.I)
_IMPLICIT = re.compile(r"IMPLICIT\s+(.*)$", re.I)
# declarations: REAL, DOUBLE PRECISION, INTEGER, DIMENSION (scalars and arrays)
_DECLARE = re.compile(rf"({_TYPE}|DIMENSION)\s+([A-Za-z].*)$", re.I)
_DATA = re.compile(r"DATA\s+(.*)$", re.I)
_PARAMETER = re.compile(r"PARAMETER\s*\((.*)\)\s*$", re.I)
_SAVE = re.compile(r"SAVE\b\s*(.*)$", re.I)
_CONTINUE = re.compile(r"CONTINUE\s*$", re.I)
_DO_LABEL = re.compile(r"DO\s+(\d+)", re.I)  # a labelled DO's label
_RETURN = re.compile(r"RETURN\s*$", re.I)
# CHARACTER*20 A, B*8, C*(*) and CHARACTER A*80: texts (for TTUTIL's FATALERR)
_CHARACTER = re.compile(r"CHARACTER\s*(?:\*\s*(?:\d+|\(\s*\*\s*\)))?\s+([A-Za-z].*)$",
                        re.I)
_TEXT_ITEM = re.compile(r"([A-Za-z]\w*)\s*(?:\*\s*(?:\d+|\(\s*\*\s*\)))?")
_QUOTED = r"'(?:[^']|'')*'"
_TEXT_ASSIGN = re.compile(rf"([A-Za-z]\w*)\s*=\s*({_QUOTED})$")
# TTUTIL's FATALERR(MODULE, MESSAGE): says both and stops the program
_FATALERR = re.compile(rf"((?:IF\s*\(.*\)\s*)?)CALL\s+FATALERR\s*\(\s*({_QUOTED}|[A-Za-z]\w*)"
                       rf"\s*,\s*({_QUOTED}|[A-Za-z]\w*)\s*\)$", re.I)
# STOP, STOP 'text' or STOP 123, alone or as a logical IF's statement
_STOP = re.compile(r"((?:IF\s*\(.*\)\s*)?)STOP\b\s*('(?:[^']|'')*'|\d+)?\s*$", re.I)
# columns 73-80 of a punched card: blank, or a sequence number (letters, then digits)
_SEQUENCE = re.compile(r"[ \t]*(?:[A-Za-z]{0,6}[0-9]{1,8}[ \t]*)?")
# Fortran's arithmetic IF: IF (e) l1, l2, l3
_ARITHMETIC_IF = re.compile(r"IF\s*\((.*)\)\s*(\d+)\s*,\s*(\d+)\s*,\s*(\d+)\s*$", re.I)
# refused by name: (pattern, the construct as a reader knows it)
_REFUSED = [
    (re.compile(r"(CHARACTER)\b", re.I), "a {0} declaration of Fortran 90's form"),
    (re.compile(r"GO\s*TO\s*\(", re.I), "a computed GO TO"),
    (re.compile(r"(COMMON|EQUIVALENCE|EXTERNAL|"
                r"FUNCTION|ENTRY|READ|WRITE|FORMAT|OPEN|CLOSE)\b", re.I),
     "Fortran's {0} in a subroutine"),
]
# Fortran's INTEGER functions, and the generic ones that are INTEGER of INTEGERs
_WHOLE = {"INT", "NINT", "IFIX", "IDINT", "IDNINT"}
_WHOLE_OF_WHOLE = {"MOD", "MAX", "MIN", "MAX0", "MIN0", "ABS", "IABS", "SIGN", "ISIGN",
                   "DIM", "IDIM"}
_NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][+-]?\d+)?"


@dataclass(frozen=True)
class Subroutine:
    """A SUBROUTINE, or a FUNCTION: then its last parameter is its name, the value
    the body gives it the function's (a reference F(X) is written out as CALL F(X, r)
    with r a name of its own, `expand_functions`)."""

    name: str
    params: tuple[str, ...]
    body: tuple  # the listing's statements (Assign, If, Loop, Declare, SubroutineCall)
    span: Span
    kind: str = "SUBROUTINE"  # or "FUNCTION"
    # the arguments that are arrays (REAL X(N), X(*)): a CALL gives an array's name
    arrays: frozenset[str] = frozenset()
    # the routine's own names it keeps from CALL to CALL (SAVE, or DATA of a value it
    # changes), with their first values (DATA's, else 0)
    kept: dict[str, float] = dataclass_field(default_factory=dict)
    # its STOPs and FATALERRs: the flag each sets (STOP#line) and the TERMT it stands for
    stops: tuple[tuple[str, ast.Termt], ...] = ()

    @property
    def label(self) -> str:
        return f"{self.kind} {self.name}"


def _head(code: str) -> tuple[str, str | None, str, tuple[str, ...]] | None:
    """(SUBROUTINE or FUNCTION, a FUNCTION's type as written or None, the name, the
    parameters) of a routine's first statement, else None."""
    m = _SUBROUTINE.match(code)
    if m is not None:
        return "SUBROUTINE", None, m.group(1).upper(), _params(m.group(2))
    m = _FUNCTION.match(code)
    if m is not None:
        kind = m.group(1) and re.sub(r"\s+|\*\d+", "", m.group(1)).upper()
        return "FUNCTION", kind, m.group(2).upper(), _params(m.group(3))
    return None


def _params(text: str | None) -> tuple[str, ...]:
    return tuple(p.strip().upper() for p in (text or "").split(",") if p.strip())


def function_names(lines: list[str], first: int) -> set[str]:
    """The names of the FUNCTION subprograms in lines[first:] (after STOP): a reference
    to one in the listing, F(X), runs it (`expand_functions`)."""
    return {head[2] for _, _, code, _ in _statements(lines, first)
            if (head := _head(code)) is not None and head[0] == "FUNCTION"}


def _split(text: str) -> list[str]:
    """text split at the commas outside parentheses and quotes."""
    out, depth, start, quoted = [], 0, 0, False
    for i, ch in enumerate(text):
        if ch == "'":
            quoted = not quoted  # ('' inside a text toggles twice: still inside)
        if quoted:
            continue
        depth += (ch == "(") - (ch == ")")
        if ch == "," and depth == 0:
            out.append(text[start:i])
            start = i + 1
    out.append(text[start:])
    return [x.strip() for x in out if x.strip()]


def _declared(text: str) -> list[tuple[str, str | None]]:
    """(NAME, its sizes as written or None) of each name a declaration lists."""
    out = []
    for item in _split(text):
        m = re.fullmatch(r"([A-Za-z]\w*)\s*(?:\((.*)\))?", item)
        if m is None:
            raise ValueError(item)
        out.append((m.group(1).upper(), m.group(2)))
    return out


def _data(text: str, sizes: dict[str, int]) -> list[str]:
    """`DATA names /values/ [, names /values/]...` as assignments, one per element, in
    Fortran's order (a whole array's elements first to last; `3*0.` three values)."""
    out = []
    for names, values in re.findall(r"([^/]+)/([^/]*)/\s*,?", text):
        targets = []
        for name, sub in _declared(names):
            if sub is None and name in sizes:
                targets += [f"{name}({k})" for k in range(1, sizes[name] + 1)]
            else:
                targets.append(name if sub is None else f"{name}({sub})")
        got = []
        for v in _split(values):
            # (.TRUE. and .FALSE. are 1 and 0, as LOGICAL variables are read)
            v = re.sub(r"\.TRUE\.", "1.", re.sub(r"\.FALSE\.", "0.", v, flags=re.I),
                       flags=re.I)
            m = re.fullmatch(rf"(?:(\d+)\s*\*\s*)?({_NUMBER})", v.replace(" ", ""))
            if m is None:
                raise ValueError(v)
            got += [m.group(2)] * int(m.group(1) or 1)
        if len(got) != len(targets):
            raise ValueError(f"{len(targets)} names, {len(got)} values")
        out += [f"{t} = {v}" for t, v in zip(targets, got, strict=True)]
    if not out:
        raise ValueError(text)
    return out


def read_subroutines(lines: list[str], first: int, path: str | None,
                     errors: list[Diagnostic], parser, called: set[str]
                     ) -> dict[str, Subroutine | None]:
    """The subroutines `called` in lines[first:] (0-based; diagnostics count lines from
    1); None for one whose faults are said (its CALLs add nothing to them). The other
    text after STOP (notes, data, routines nothing calls) is not read. `parser`: the
    listing's own (the statements of a body are read by its grammar)."""
    written: dict[str, list] = {}
    for unit in _units(_statements(lines, first), errors):
        kind, _, name, _ = _head(unit[0][2])
        if name in written:
            if name in called:
                errors.append(Diagnostic(f"{kind} {name} is written twice",
                                         Span(unit[0][0] + 1, unit[0][1] + 1),
                                         "a subroutine has one definition"))
            continue
        written[name] = unit
    units: dict[str, Subroutine | None] = {}
    functions = {n for n, unit in written.items() if _head(unit[0][2])[0] == "FUNCTION"}
    wanted = sorted(called)
    while wanted:  # (the routines called, and those they call)
        name = wanted.pop()
        if name in units or name not in written:
            continue
        units[name] = sub = _read_unit(written[name], lines, path, errors, parser,
                                       functions)
        if sub is not None:
            wanted += [n.name for st in sub.body for n in ast.walk(st)
                       if isinstance(n, ast.SubroutineCall)]
            wanted += [n.func for st in sub.body for n in ast.walk(st)
                       if isinstance(n, ast.Call) and n.func in written]
    return units


def _statements(lines: list[str], first: int) -> list[tuple[int, int, str, str]]:
    """(line index, column of the code, code, label) of each statement of the
    SUBROUTINE ... END units, fixed form: columns 7 to 72, or to 132 where a line
    goes on past 72 with more than a card's sequence number (FSE's compilers read
    extended source: LINTUL2-Cassava's routines have lines of 102 columns),
    continuation lines joined to the statement they continue; the lines outside the
    units are not read."""
    out: list[list] = []
    inside = False
    for k in range(first, len(lines)):
        line = lines[k].rstrip("\n").expandtabs(6)
        line = line[:72] if _SEQUENCE.fullmatch(line[72:]) else line[:132]
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
        if _END.match(code.strip()):
            inside = False
    return [(k, col, code, label) for k, col, code, label in out]


def _units(statements, errors: list[Diagnostic]):
    """The statements of each SUBROUTINE (or FUNCTION) ... END."""
    unit: list | None = None
    for st in statements:
        code = st[2]
        if unit is None:
            if _head(code) is not None:
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


def _read_unit(unit, file_lines: list[str], path: str | None, errors: list[Diagnostic],
               parser, functions: set[str] = frozenset()) -> Subroutine | None:
    """One routine read (None: its faults are said); `file_lines`: the file's;
    `functions`: the FUNCTIONs written after STOP, whose references it may hold."""
    n_lines = len(file_lines)
    from .blocks import Nester
    from .build import Builder

    k0, col0, code0, _ = unit[0]
    kind, typed, name, params = _head(code0)
    routine = f"{kind} {name}"
    span = Span(k0 + 1, col0 + 1, k0 + 1, col0 + 1 + len(code0))
    if kind == "FUNCTION":
        params += (name,)  # (its value: the last argument, one the body assigns)
    body = unit[1:-1]
    real_all, declared, bad, none = False, set(), False, False
    integers: set[str] = set()  # declared INTEGER
    if typed is not None:
        (integers if typed == "INTEGER" else declared).add(name)
    by_dimension: dict[str, Span] = {}  # arrays DIMENSION declares (typed implicitly)
    sizes: dict[str, int] = {}  # the routine's own arrays and their lengths
    data: dict[str, tuple[int, str]] = {}  # names DATA or PARAMETER give: (line, which)
    executable: list = []
    stops: set[int] = set()  # the lines of STOPs (read as TERMTs)
    array_params: set[str] = set()  # the arguments that are arrays
    saved: set[str] = set()  # the names SAVE lists ("*": every one)
    texts: dict[str, str | None] = {}  # CHARACTER names and their texts
    fatals: set[int] = set()  # the lines of FATALERR's CALLs (read as TERMTs)
    data_values: dict[str, float] = {}  # the values DATA gives to scalars

    def refuse(what: str, where: Span, instead: str) -> None:
        nonlocal bad
        errors.append(Diagnostic(what, where, instead))
        bad = True

    ends = {label.lstrip("0") for _, _, code, label in body if label and _CONTINUE.match(code)}
    starts = {m.group(1).lstrip("0") for _, _, code, _ in body if (m := _DO_LABEL.match(code))}
    jumped_to = {m.group(1).lstrip("0") for _, _, code, _ in body
                 for m in re.finditer(r"GO\s*TO\s*(\d+)", code, re.I)}
    jumped_to |= {n.lstrip("0") for _, _, code, _ in body
                  if (m := _ARITHMETIC_IF.match(code)) for n in m.groups()[1:]}
    for i, (k, col, code, label) in enumerate(body):
        where = Span(k + 1, col + 1, k + 1, col + 1 + len(code))
        do = _DO_LABEL.match(code)
        if do and do.group(1).lstrip("0") not in ends:
            refuse(f"DO {do.group(1)} (in {routine}): no {do.group(1)} CONTINUE "
                   f"in {routine} ends it", where,
                   f"end the loop with {do.group(1)} CONTINUE before the routine's END")
            continue
        if label and _RETURN.match(code) and label.lstrip("0") in jumped_to:
            # `99 RETURN` a GO TO names: its place, then the RETURN (the last statement)
            executable.append((k, 0, f"{label:<5} CONTINUE"))
            label = ""
        if label and _CONTINUE.match(code):
            # the end of the DO loops with this label, or a place a GO TO jumps to
            # (parse/jumps.py); else it does nothing
            if label.lstrip("0") in starts | jumped_to:
                executable.append((k, 0, f"{label:<5} {code}"))  # (the listing reads it so)
            continue
        if label and any(p.match(code) for p in (_IMPLICIT, _DECLARE, _DATA, _PARAMETER,
                                                 _SAVE)):
            refuse(f"the statement label {label} on a declaration (in {routine}): not "
                   "supported", where, "label an executable statement or a CONTINUE")
            continue
        implicit = _IMPLICIT.match(code)
        if implicit:
            what = implicit.group(1).replace(" ", "").upper()
            if what == "REAL(A-Z)":
                real_all = True
            elif what == "NONE":
                none = True
            else:
                refuse(f"IMPLICIT {implicit.group(1)}: not supported", where,
                       "write IMPLICIT REAL (A-Z)")
            continue
        declare = _DECLARE.match(code)
        if declare:
            word = declare.group(1).split("*")[0].upper()
            integer = word == "INTEGER"
            try:
                names = _declared(declare.group(2))
            except ValueError as exc:
                refuse(f"{word} {exc}: not a declaration the subset reads", where,
                       "write NAME or NAME(n), n a number")
                continue
            for n, dims in names:
                if dims is None:
                    (integers if integer else declared).add(n)
                    continue
                # (an array argument: the CALL's array stands for it, its elements read
                # where the body reads X(I); its size is the caller's, of one subscript
                # numbered from 1: Fortran's X(2:5) numbers it otherwise, refused below)
                if n in params and not integer and word != "LOGICAL" and "," not in dims \
                        and re.fullmatch(r"\s*(?:1\s*:\s*)?(?:[1-9]\d*|[A-Za-z]\w*|\*)\s*",
                                         dims):
                    array_params.add(n)
                    declared.add(n)
                    continue
                if n in params or integer or word == "LOGICAL" or \
                        not re.fullmatch(r"\s*\d+\s*", dims):
                    what = "an INTEGER array" if integer else \
                        "a LOGICAL array" if word == "LOGICAL" else \
                        "an array argument of more than one subscript, or numbered from " \
                        "other than 1" if n in params else \
                        "an array of more than one subscript, or of a size not a number"
                    refuse(f"{n}({dims}) in {routine}: {what} is not supported",
                           where, f"declare it REAL {n}(N) or {n}(*), numbered from 1"
                           if n in params else "the subset's arrays are the routine's own "
                           "REAL X(n)")
                    continue
                sizes[n] = int(dims)
                if word == "DIMENSION":
                    by_dimension[n] = where
                else:
                    declared.add(n)
                executable.append((k, col, f"DIMENSION {n}({int(dims)})"))
            continue
        given = _DATA.match(code)
        if given:
            try:
                lines = _data(given.group(1), sizes)
            except ValueError as exc:
                refuse(f"DATA {given.group(1)}: not read ({exc})", where,
                       "write DATA X /1.0, 2.0/ with as many values as names, X "
                       "declared before")
                continue
            for line in lines:
                target, value = (x.strip() for x in line.split("="))
                data.setdefault(target.split("(")[0].upper(), (k + 1, "DATA"))
                if "(" not in target:  # (a scalar's first value, if the routine keeps it)
                    data_values[target.upper()] = float(value.replace("D", "E")
                                                        .replace("d", "e"))
            executable.append((k, col, "; ".join(lines)))
            continue
        constants = _PARAMETER.match(code)
        if constants:
            # (named constants: assignments first thing, the routine may not assign them)
            items = _split(constants.group(1))
            if any("=" not in c for c in items):
                refuse(f"PARAMETER ({constants.group(1)}): not read", where,
                       "write PARAMETER (NAME = value, ...)")
                continue
            numbers = []
            for c in items:
                name, _, value = (x.strip() for x in c.partition("="))
                if value.startswith("'"):  # (a text, for FATALERR: as NAME = 'text')
                    if name.upper() not in texts or texts[name.upper()] is not None:
                        refuse(f"PARAMETER ({c}) in {routine}: a text for a name not "
                               "declared CHARACTER, or given twice", where,
                               f"declare CHARACTER*20 {name} before it")
                    else:
                        texts[name.upper()] = value[1:-1].replace("''", "'")
                    continue
                data.setdefault(name.upper(), (k + 1, "PARAMETER"))
                numbers.append(c)
            if numbers:
                executable.append((k, col, "; ".join(numbers)))
            continue
        saves = _SAVE.match(code)
        if saves:
            # (what SAVE keeps matters only for a name read before the routine assigns
            # it: `Subroutine.kept`)
            listed = saves.group(1).strip()
            saved |= {n for n, _ in _declared(listed)} if listed else {"*"}
            continue
        if _RETURN.match(code):
            if any(not _RETURN.match(c) for _, _, c, _ in body[i + 1:]):
                refuse(f"RETURN before the end of {routine}: not supported", where,
                       "write the statements after it in the ELSE of an IF")
            continue
        chars = _CHARACTER.match(code)
        if chars:
            # (texts: the messages TTUTIL's FATALERR says; never a number)
            items = _split(chars.group(1))
            if not all(_TEXT_ITEM.fullmatch(it) for it in items):
                refuse(f"CHARACTER {chars.group(1)}: not a declaration the subset reads",
                       where, "write CHARACTER*20 NAME or CHARACTER NAME*20")
                continue
            for it in items:
                n = _TEXT_ITEM.fullmatch(it).group(1).upper()
                if n in params:
                    refuse(f"{n} in {routine}: a CHARACTER argument is not supported",
                           where, "give the text in the routine: NAME = 'text'")
                texts.setdefault(n, None)
            continue
        given_text = _TEXT_ASSIGN.match(code)
        if given_text and given_text.group(1).upper() in texts:
            n = given_text.group(1).upper()
            if texts[n] is not None or label:
                refuse(f"{n} = {given_text.group(2)} (in {routine}): a text given twice, "
                       "or at a label, is not supported", where,
                       "give each text its own CHARACTER name, once")
                continue
            texts[n] = given_text.group(2)[1:-1].replace("''", "'")
            continue
        fatal = _FATALERR.match(code)
        if fatal is None and re.search(r"\bCALL\s+FATALERR\b", code, re.I):
            refuse(f"{code.strip()} (in {routine}): CALL FATALERR takes two texts, the "
                   "module's name and the message", where,
                   "write CALL FATALERR ('MODULE', 'message')")
            continue
        if fatal is not None:
            said = []
            for arg in fatal.group(2, 3):
                if arg.startswith("'"):
                    said.append(arg[1:-1].replace("''", "'"))
                elif texts.get(arg.upper()) is not None:
                    said.append(texts[arg.upper()])
                else:
                    refuse(f"FATALERR's {arg} (in {routine}): not a text given before",
                           where, "give FATALERR a text in quotes, or a CHARACTER name "
                           "given one before the CALL")
                    break
            else:
                text = f"FATALERR in {said[0]}: {said[1]}".replace("'", "''")
                code = fatal.group(1) + f"TERMT(1.0, '{text}')"
                fatals.add(k + 1)
        stop = _STOP.match(code)
        if stop is not None:
            # (Fortran's STOP ends the program: the run ends there, saying the
            # routine's words, as TERMT ends it)
            said = stop.group(2)[1:-1] if stop.group(2) and stop.group(2).startswith("'") \
                else f"STOP {stop.group(2) or ''}".strip()
            code = stop.group(1) + "TERMT(1.0, '" + said + "')"
            stops.add(k + 1)
        found = next(((m, what) for p, what in _REFUSED if (m := p.match(code))), None)
        if found is not None:
            match, what = found
            word = (match.group(1) or "").upper() if match.groups() else ""
            refuse(f"{what.format(word)} ({routine}, line {k + 1}): not supported",
                   where, "the subroutines after STOP run assignments, IFs, DO loops, "
                   "the routine's own arrays with DATA, and CALLs of the others")
            continue
        arithmetic = _ARITHMETIC_IF.match(code)
        if arithmetic:
            # Fortran's arithmetic IF (e) l1, l2, l3: to l1 where e < 0, l2 where e = 0,
            # l3 where e > 0; forward jumps, as GO TO's (parse/jumps.py)
            e, below, zero, above = arithmetic.groups()
            if re.search(r"\.(?:GT|GE|LT|LE|EQ|NE|AND|OR|NOT|EQV|NEQV)\.|[<>]|==|/=", e,
                         re.I):
                refuse(f"IF ({e}) {below}, {zero}, {above} (in {routine}): an arithmetic "
                       "IF takes a number, not a test", where,
                       f"write IF ({e}) GO TO {above}, or IF ({e}) THEN ... END IF")
                continue
            code = (f"IF (({e}) .LT. 0.) GO TO {below}; IF (({e}) .EQ. 0.) GO TO {zero}; "
                    f"GO TO {above}")
        # (DO 10, I = 1, N: the comma a blank, the columns as they are)
        code = re.sub(r"^(DO\s+\d+\s*),", r"\1 ", code, flags=re.I)
        if label:  # (a place a GO TO jumps to: `10: X = 1.0`, the code where it was)
            executable.append((k, 0, f"{label}:".ljust(max(col, len(label) + 2)) + code))
        else:
            executable.append((k, col, code))
    for n, where in by_dimension.items():
        if n in integers or (not real_all and n not in declared and n[:1] in "IJKLMN"):
            refuse(f"{n} in {routine}: an INTEGER array (by Fortran's implicit "
                   "typing) is not supported", where, f"declare it REAL {n}(...)")
        elif none and n not in declared:
            refuse(f"{n} is not declared (IMPLICIT NONE in {routine})", where,
                   f"declare it: REAL {n}")
        else:
            declared.add(n)
    if bad:
        return None
    # the executable statements read by the listing's own grammar (ACSL form: IF blocks,
    # .LT. and the rest), each at its own line and column
    text = ["" for _ in range(n_lines)]
    text[k0] = "PROGRAM " + name  # (where the SUBROUTINE line is: every line in its place)
    for k, col, code in executable:
        text[k] = (text[k] + "; " if text[k] else " " * col) + code
    end_k, _, _, end_label = unit[-1]
    if end_label and end_label.lstrip("0") in jumped_to:
        # `99 END` a GO TO names: its place (a CONTINUE), then the END on a line of its own
        text[end_k] = f"{end_label:<5} CONTINUE"
        end_k += 1
        text += [""] * max(0, end_k + 1 - len(text))
    text[end_k] = "END"
    source = "\n".join(text) + "\n"
    # (a line read in other words than written -- a statement continued onto it joined,
    # DATA and PARAMETER as assignments, an arithmetic IF as GO TOs, a label -- has no
    # text of its own for the messages to quote: a span on it keeps its line and the
    # statement's first column, where a column of the text read may lie past the
    # line's end, or belong to another line of a statement continued)
    rewritten = {k + 1 for k, line in enumerate(text)
                 if line.strip() and not (k < n_lines and
                                          file_lines[k].startswith(line.rstrip()))}
    starts = {k: len(file_lines[k - 1]) - len(file_lines[k - 1].lstrip()) + 1
              if k <= n_lines else 1 for k in rewritten}

    def at_statement(span: Span | None) -> Span | None:
        return Span(span.line, starts[span.line]) if span is not None and \
            span.line in rewritten else span
    from lark.exceptions import UnexpectedInput

    from .errors import syntax_diagnostic
    from .lexical import prepare
    from .tree import read

    try:
        tree = read(parser, prepare(source))
    except UnexpectedInput as exc:
        said = syntax_diagnostic(exc, prepare(source), parser)
        errors.append(replace(said, span=at_statement(said.span)))
        return None
    builder = Builder(source, path, parser)
    builder.acsl = True
    items = builder.statements(tree)
    _, _, statements = Nester(builder.errors).nest(items)
    statements = lower_jumps(statements, builder.errors)
    errors.extend(replace(d, span=at_statement(d.span)) for d in builder.errors)
    if builder.errors:
        return None
    allowed = (ast.Assign, ast.If, ast.Loop, ast.Declare, ast.SubroutineCall)

    # (a STOP sets a flag where it is reached, in written order, and the listing's CALL
    # stops the run where the flag is set, saying it is the routine's STOP or FATALERR:
    # a STOP in an ELSE, after a GO TO or in a DO loop is reached as Fortran reaches
    # it; the flag starts at 0 at every CALL)
    flags: list[tuple[str, ast.Termt]] = []

    def flagged(st):
        if isinstance(st, ast.Termt) and st.span.line in stops | fatals:
            flag = f"STOP#{st.span.line}"
            if all(f != flag for f, _ in flags):
                flags.append((flag, replace(st, written=(
                    "STOP in " if st.span.line in stops else "CALL FATALERR in ") + routine)))
            return ast.Assign((flag,), (st.span,), ast.Num(1.0, st.span, "1"), st.span)
        return ast.with_bodies(st, lambda body: [flagged(b) for b in body])
    statements = [flagged(st) for st in statements]
    statements = [ast.Assign((f,), (t.span,), ast.Num(0.0, t.span, "0"), t.span)
                  for f, t in flags] + statements
    text_read = next((n for st in statements for n in ast.walk(st)
                      if (isinstance(n, ast.Name) and n.name in texts) or
                      (isinstance(n, ast.Assign) and n.targets[0] in texts)), None)
    if text_read is not None:
        n = text_read.name if isinstance(text_read, ast.Name) else text_read.targets[0]
        errors.append(Diagnostic(
            f"{n} is CHARACTER (a text) in {routine}: the subset's texts are FATALERR's "
            "messages, given once in quotes", text_read.span,
            f"compute with numbers; give {n} its text once, NAME = 'text'"))
        return None
    if rewritten:
        statements = [ast.rebuilt(st, lambda v: at_statement(v) if isinstance(v, Span)
                                  else v) for st in statements]
    for st in (n for top in statements for n in ast.walk(top)):
        if isinstance(st, ast.STATEMENTS) and not isinstance(st, allowed):
            errors.append(Diagnostic(
                f"this statement in {routine}: not supported", st.span,
                "the subroutines after STOP run assignments, IFs, DO loops and CALLs"))
            return None
    body_nodes = tuple(statements)
    declared |= {f for f, _ in flags}  # (the STOPs' flags: the reader's own REALs)
    fault = _typing(body_nodes, declared, integers, real_all, none, routine,
                    functions) or \
        _data_kept(body_nodes, data, routine, data_values)
    if fault is not None:
        errors.append(fault)
        return None
    # the names the routine keeps from one CALL to the next: those SAVE names, and a
    # scalar DATA gives a value the routine changes (Fortran keeps it so); such a DATA
    # value is then the first, not one given at every CALL
    changed = {n.targets[0] for st in body_nodes for n in ast.walk(st)
               if isinstance(n, ast.Assign) and n.targets[0] in data_values
               and n.span.line != data[n.targets[0]][0]}
    if changed:
        body_nodes = tuple(_without_data(body_nodes, {n: data[n][0] for n in changed}))
    kept = {n: data_values.get(n, 0.0) for n in _locals(body_nodes, params)
            if "*" in saved or n in saved or n in changed}
    return Subroutine(name, params, body_nodes, span, kind, frozenset(array_params), kept,
                      tuple(flags))


def _locals(body, params) -> set[str]:
    """The names a routine's body assigns that are not its arguments."""
    return {n for st in body for node in ast.walk(st) if isinstance(node, ast.Assign)
            for n in node.targets} - set(params)


def _without_data(body, lines: dict[str, int]) -> list:
    """The body without the assignments DATA made of these names (at these lines)."""
    return [ast.with_bodies(st, lambda b: _without_data(b, lines)) for st in body
            if not (isinstance(st, ast.Assign) and lines.get(st.targets[0]) == st.span.line)]


def _typing(body, declared: set[str], integers: set[str], real_all: bool, none: bool,
            routine: str, functions: set[str] = frozenset()) -> Diagnostic | None:
    """Fortran's types where they would give other numbers than the listing's real
    arithmetic: a name not declared under IMPLICIT NONE; an INTEGER (declared, or by
    Fortran's implicit typing, I to N) given a value that is no whole number, or
    divided by one (Fortran truncates both). A reference to one of the FUNCTIONs
    written after STOP has the type its name has here, as in Fortran."""
    def integer(n: str) -> bool:
        return n in integers or (not real_all and not none and n not in declared
                                 and n[:1] in "IJKLMN")

    def whole(e) -> bool:  # (an expression Fortran computes in integers)
        if isinstance(e, ast.Num):
            return not re.search(r"[.EeDd]", e.text or repr(e.value))
        if isinstance(e, ast.Name):
            return integer(e.name)
        if isinstance(e, ast.BinOp) and e.op in ("+", "-", "*", "**", "/"):
            return whole(e.left) and whole(e.right)
        if isinstance(e, ast.Neg):
            return whole(e.operand)
        if isinstance(e, ast.Call):
            return e.func in _WHOLE or (e.func in _WHOLE_OF_WHOLE and all(map(whole, e.args))) \
                or (e.func in functions and integer(e.func))
        return False

    def fault(message: str, span, hint: str) -> Diagnostic:
        return Diagnostic(f"{message} ({routine})", span, hint)

    for node in (n for st in body for n in ast.walk(st)):
        names = [node.name] if isinstance(node, ast.Name) else \
            list(node.targets) if isinstance(node, ast.Assign) else \
            [node.var] if isinstance(node, ast.Loop) else []
        for n in names:
            if none and n not in declared and n not in integers and "#" not in n:
                return Diagnostic(f"{n} is not declared (IMPLICIT NONE in "
                                  f"{routine})", node.span, f"declare it: REAL {n}")
        if isinstance(node, ast.Assign) and not node.subscripts and \
                integer(node.targets[0]) and not whole(node.expr):
            return Diagnostic(
                f"{node.targets[0]} is an INTEGER ({routine}): Fortran would cut "
                "this value to a whole number, which is not supported", node.span,
                f"write IMPLICIT REAL (A-Z), or declare it REAL {node.targets[0]}")
        if isinstance(node, ast.BinOp) and node.op == "/" and whole(node.left) and \
                whole(node.right):
            return Diagnostic(
                f"a division of whole numbers ({routine}): Fortran's integer "
                "division, which cuts the quotient, is not supported", node.span,
                "write REAL(I)/REAL(J), or declare the names REAL")
        if isinstance(node, ast.BinOp) and node.op == "**" and whole(node.left) and \
                whole(node.right) and not (isinstance(node.right, ast.Num)
                                           and node.right.value >= 0):
            return fault("a power of whole numbers whose exponent may be negative: "
                         "Fortran's is then 0 or 1, which is not supported", node.span,
                         "write REAL(I)**J, or declare the names REAL")
        if isinstance(node, ast.Loop):
            if integer(node.var) and not all(whole(e) for e in (node.start, node.stop,
                                                                  node.step) if e is not None):
                return fault(f"the bounds of DO {node.var}, an INTEGER, are no whole numbers: "
                             "Fortran cuts them, which is not supported", node.span,
                             "write whole-number bounds, or declare the variable REAL")
            assigned = next((n for st in node.body for n in ast.walk(st)
                             if isinstance(n, ast.Assign) and node.var in n.targets), None)
            if assigned is not None:
                return fault(f"{node.var} is assigned inside its own DO loop, which Fortran "
                             "does not allow", assigned.span,
                             f"use another name for the value, not {node.var}")
    return None


def _data_kept(body, data: dict[str, tuple[int, str]], routine: str,
               scalars: dict[str, float]) -> Diagnostic | None:
    """An array DATA gives values that the routine also assigns keeps its last values
    from call to call in Fortran (as SAVE would): refused (a scalar is kept:
    `Subroutine.kept`); a PARAMETER assigned is no Fortran."""
    for node in (n for st in body for n in ast.walk(st)):
        if not (isinstance(node, ast.Assign) and node.targets[0] in data) or \
                node.targets[0] in scalars:
            continue
        line, which = data[node.targets[0]]
        if node.span.line == line:
            continue
        if which == "PARAMETER":
            return Diagnostic(
                f"{node.targets[0]} is a PARAMETER of {routine}: Fortran does not "
                "let the routine assign it", node.span,
                f"give the value another name, or remove {node.targets[0]} from PARAMETER")
        if which == "DATA":
            return Diagnostic(
                f"{node.targets[0]} has its value from DATA and is assigned in "
                f"{routine}: Fortran keeps its value from one CALL to the next (as SAVE), "
                "which is not supported", node.span,
                f"give {node.targets[0]} its value with an assignment first thing in the "
                "routine")
    return None


def expand_functions(statements, functions: set[str], counts: dict[str, int]) -> list:
    """The statements with each reference to a FUNCTION subprogram (`functions`),
    F(X), written as a CALL before the statement that holds it, CALL F(X, F#k), and
    the name F#k where the reference was (the k-th of F's: `counts`). The arguments'
    own references come first; a reference in an IF's condition (an ELSE IF's too)
    or a DO loop's bounds comes before the IF or the loop (a FUNCTION computes its
    value and changes nothing else: the subset refuses the rest)."""
    from dataclasses import replace

    def pull(e, calls: list):
        if e is None or not isinstance(e, ast.Node):
            return e
        changes = {}
        for field in e.child_fields:
            value = getattr(e, field)
            new = tuple(pull(v, calls) for v in value) if isinstance(value, tuple) else \
                pull(value, calls)
            if new != value:
                changes[field] = new
        e = replace(e, **changes) if changes else e
        if isinstance(e, ast.Call) and e.func in functions:
            counts[e.func] = k = counts.get(e.func, 0) + 1
            value = ast.Name(f"{e.func}#{k}", e.span)
            calls.append(ast.SubroutineCall(e.func, e.args + (value,), e.span))
            return value
        return e

    def statement(st, calls: list):
        if isinstance(st, ast.Assign):
            return replace(st, expr=pull(st.expr, calls),
                           subscripts=tuple(pull(x, calls) for x in st.subscripts))
        if isinstance(st, ast.If):
            return replace(st, branches=tuple(
                replace(b, cond=pull(b.cond, calls), body=tuple(each(b.body)))
                for b in st.branches))
        if isinstance(st, ast.Loop):
            return replace(st, start=pull(st.start, calls), stop=pull(st.stop, calls),
                           step=pull(st.step, calls), body=tuple(each(st.body)))
        if isinstance(st, ast.SubroutineCall):
            return replace(st, args=tuple(pull(a, calls) for a in st.args))
        if isinstance(st, (ast.Block, ast.Procedural, ast.FunctionDef)):
            return ast.with_bodies(st, each)
        return pull(st, calls)  # (TERMT, SCHEDULE, ...: their expressions)

    def each(body) -> list:
        out: list = []
        for st in body:
            calls: list = []
            st = statement(st, calls)
            out += calls + [st]
        return out

    return each(statements)


def expand_calls(statements: list, subroutines: dict[str, Subroutine | None],
                 errors: list[Diagnostic]) -> list:
    """The statements with each CALL of a subroutine written out as a PROCEDURAL, and
    each reference to a FUNCTION as a CALL of it first (`expand_functions`)."""
    from .macros import _assigned, _rename

    counts: dict[str, int] = {}
    bodies: dict[str, tuple | None] = {}  # each routine's body, its own CALLs written out
    arrays = _declared_arrays(statements)
    data_names = {it.name for st in ast.every_statement(statements)
                  if isinstance(st, ast.Data) for it in st.items}
    changed_data: set[str] = set()  # the PARAMs routines change
    stop_termts = {f: t for sub in subroutines.values() if sub is not None
                   for f, t in sub.stops}
    functions = {n for n, sub in subroutines.items() if sub is not None and
                 sub.kind == "FUNCTION"}
    references: dict[str, int] = {}

    def body_of(sub: Subroutine, stack: tuple[str, ...]) -> tuple | None:
        if sub.name not in bodies:
            if sub.name in stack:
                errors.append(Diagnostic(
                    f"{sub.label} calls itself (through "
                    f"{' -> '.join(stack + (sub.name,))}): Fortran 77 has no recursion",
                    sub.span, "write the repetition as a DO loop"))
                return None
            before = len(errors)
            written = expand_functions(sub.body, functions, references)
            out = tuple(x for st in written for x in one(st, stack + (sub.name,)))
            bodies[sub.name] = out if len(errors) == before else None
        return bodies[sub.name]

    def one(st, stack: tuple[str, ...] = ()):
        if not isinstance(st, ast.SubroutineCall):
            return [ast.with_bodies(st, lambda body: [x for s in body for x in one(s, stack)])]
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
            result = sub.kind == "FUNCTION"  # (its value: the last argument, not written)
            given, takes = len(st.args) - result, sub.params[:len(sub.params) - result]
            what = st.name if result else f"CALL {st.name}"
            errors.append(Diagnostic(
                f"{what} gives {given} argument(s); {sub.label} "
                f"(line {sub.span.line}) takes {len(takes)}", st.span,
                f"write {what}({', '.join(takes)})"))
            return []
        sub_body = body_of(sub, stack)
        if sub_body is None:
            return []
        assigned = _assigned(sub_body)
        own_arrays = _declared_arrays(sub_body)
        reads, everywhere = _flow(sub_body, own_arrays)
        # (an array SAVE keeps, set in an IF: where the IF does not set it, Fortran
        # keeps the last CALL's values, which no array here keeps)
        branch_set = next((n for top in sub_body for node in ast.walk(top)
                           if isinstance(node, ast.If) for b in node.branches
                           for inner in b.body for n in ast.walk(inner)
                           if isinstance(n, ast.Assign) and n.subscripts
                           and n.targets[0] in own_arrays and n.targets[0] in sub.kept),
                          None)
        if branch_set is not None:
            errors.append(Diagnostic(
                f"{branch_set.targets[0]}, an array SAVE keeps, is set in an IF in "
                f"{sub.label}: where the IF does not set it, Fortran keeps the last CALL's "
                "values, which the subset does not (SAVE keeps no array)", branch_set.span,
                "set every element on every path, first thing in the routine"))
            return []
        counts[st.name] = k = counts.get(st.name, 0) + 1
        names: dict[str, str] = {}
        values: dict[str, ast.Node] = {}
        outputs: list[str] = []
        inputs: list[str] = []
        kept: list[tuple[str, str, ast.Node]] = []  # (argument, variable, value before)
        for p, actual in zip(sub.params, st.args, strict=True):
            if p in sub.arrays:
                fault = None
                if p in assigned:
                    fault = (f"the array argument {p} of {sub.label} is assigned in it: "
                             "not supported", "pass the elements it computes as "
                             "arguments of their own")
                elif not (isinstance(actual, ast.Name) and actual.name in arrays):
                    fault = (f"argument {p} of {sub.label} is an array: the CALL must give "
                             "the name of an array", f"declare one, e.g. ARRAY {p}(1:N) "
                             f"with ARRAY_SIZE N = 10, and pass it as {p}")
                if fault is not None:
                    errors.append(Diagnostic(fault[0], st.span, fault[1]))
                    return []
                values[p] = actual
                inputs.append(actual.name)
                continue
            if p in assigned:
                # (read before the body assigns it, or left as it was on some path: the
                # routine reads the variable's value before the CALL, `kept`)
                changes = p in reads or p not in everywhere
                fault = None
                if not isinstance(actual, ast.Name):
                    fault = (f"argument {p} of {sub.label} is assigned in it: the "
                             "CALL must give a name there", f"pass a variable as {p}")
                elif changes and (stack or sub.kind == "FUNCTION") and p in reads:
                    # (kept values are the listing's CALLs': a routine's or a
                    # FUNCTION's argument has none)
                    fault = (f"argument {p} of {sub.label} is read before it is "
                             "assigned (an input and an output at once): not supported",
                             "pass its value in an argument of its own")
                elif changes and (stack or sub.kind == "FUNCTION"):
                    fault = (f"argument {p} of {sub.label} is not assigned on every "
                             "path through it (where it is not, Fortran keeps its value "
                             "from before the CALL): not supported",
                             f"give {p} a value on every path, first thing in the routine")
                elif actual.name in outputs:
                    fault = (f"the CALL gives {actual.name} to two arguments SUBROUTINE "
                             f"{st.name} assigns", "give each its own variable")
                if fault is not None:
                    errors.append(Diagnostic(fault[0], st.span, fault[1]))
                    return []
                out = actual.name
                if changes:
                    # a PARAM changed: the listing's name is the changed value from now
                    # on (read anywhere, printed, FINISH), the PARAM its first value,
                    # under a name of its own (`PARAMETER_OF`)
                    if actual.name in data_names:
                        first = ast.Name(PARAMETER_OF(actual.name), actual.span)
                        changed_data.add(actual.name)
                        before = ast.Call(KEPT, (first, ast.Name(out, actual.span)),
                                          actual.span)
                    else:
                        before = ast.Call(BEFORE, (actual,), actual.span)
                    kept.append((p, out, before))
                names[p] = out
                outputs.append(out)
            else:
                values[p] = actual
                inputs.extend(n.name for n in ast.walk(actual) if isinstance(n, ast.Name))
        both = sorted(set(outputs) & set(inputs))
        if both:
            errors.append(Diagnostic(
                f"the CALL gives {both[0]} to {sub.label} both as a value it reads "
                "and as an argument it assigns: not supported", st.span,
                "pass the value in a variable of its own"))
            return []
        params = set(sub.params)
        # (a name the routine keeps, SAVE or DATA, read before the routine assigns it:
        # the value this CALL left at the last step point; a routine's CALL of another
        # has no step points of its own, so there it is refused as any other)
        saved = {n for n in reads if n in sub.kept and not stack and n not in own_arrays}
        if saved and k > 1:
            # (Fortran keeps one copy of them, whichever CALL runs: the two CALLs'
            # order in the rates would decide the numbers)
            name = sorted(saved)[0]
            errors.append(Diagnostic(
                f"{sub.label} keeps {name} from CALL to CALL (SAVE or DATA) and is "
                f"CALLed {k} times: Fortran keeps one {name} for all of them, which is "
                "not supported", st.span,
                f"CALL {sub.name} once, or give each CALL a routine of its own"))
            return []
        unknown = sorted((n, span) for n, span in reads.items()
                         if n not in params and n not in saved)
        if unknown:
            n, span = unknown[0]
            errors.append(Diagnostic(
                f"{n} is read in {sub.label} before it has a value (its names are "
                "its own)", span, f"pass {n} as an argument, or give it a value before"
                + (" (SAVE keeps no array here)" if n in sub.kept and n in own_arrays
                   else f" (SAVE keeps {n} only where the listing CALLs {sub.name})"
                   if n in sub.kept else "")))
            return []
        local = {n: f"{st.name}#{k}.{n}" for n in assigned - params}
        names |= local
        for n in sorted(saved):
            kept.append((n, local[n], ast.Call(KEPT, (
                ast.Num(sub.kept[n], st.span, repr(sub.kept[n])),
                ast.Name(local[n], st.span)), st.span)))
        body = tuple(_rename(s, names, values) for s in sub_body)
        # (each changed variable starts from its value before the CALL, computed
        # outside the PROCEDURAL: library's BEFORE and KEPT)
        before_calls = []
        for p, out, before in kept:
            given = f"{st.name}#{k}.{p}.BEFORE"
            before_calls.append(ast.Assign((given,), (st.span,), before, st.span))
            body = (ast.Assign((out,), (st.span,), ast.Name(given, st.span), st.span),
                    *body)
            inputs.append(given)
        # (the routine's arrays are declared where the listing declares its own: no
        # declaration stands in a PROCEDURAL)
        declared: list = []

        def hoist(statements):
            declared.extend(s for s in statements if isinstance(s, ast.Declare))
            return [ast.with_bodies(s, hoist) for s in statements
                    if not isinstance(s, ast.Declare)]
        body = tuple(hoist(body))
        # (the routine's own names are outputs too: each call's, shown as NAME#k.X)
        # (the listing's CALL stops the run where a STOP's flag is set, in this
        # routine or one it CALLs: a TERMT of the listing, said as the STOP)
        stopping = [] if stack else [
            ast.Termt(ast.BinOp(">", ast.Name(local[n], t.span), ast.Num(0.5, t.span, "0.5"),
                                t.span), t.span, t.message, t.written, ends_job=True)
            for n in sorted(local) if (t := stop_termts.get(n.rsplit(".", 1)[-1]))]
        return declared + before_calls + [ast.Procedural(
            tuple(dict.fromkeys(outputs + sorted(local.values()))),
            tuple(dict.fromkeys(inputs)), body, st.span)] + stopping

    out = [x for st in expand_functions(statements, functions, references)
           for x in one(st)]
    def renamed(st):
        if isinstance(st, ast.Data):
            return replace(st, items=tuple(
                replace(it, name=PARAMETER_OF(it.name)) if it.name in changed_data else it
                for it in st.items))
        return ast.with_bodies(st, lambda body: [renamed(b) for b in body])
    return [renamed(st) for st in out] if changed_data else out


def _declared_arrays(statements) -> frozenset[str]:
    """The names declared arrays (with sizes) anywhere in the statements."""
    return frozenset(n for st in ast.every_statement(statements)
                     if isinstance(st, ast.Declare)
                     for n, sizes in zip(st.names, st.sizes or (), strict=False) if sizes)


def PARAMETER_OF(name: str) -> str:
    """The name of the PARAM a routine changes, its first value (LINGRA's INCUT: the
    listing's INCUT is the count from then on, `INCUT#PARAM` the PARAM)."""
    return f"{name}#PARAM"


def _flow(body, arrays: frozenset[str] = frozenset()) -> tuple[dict[str, object], set[str]]:
    """The names read where no assignment before them (in written order, on every
    path) has given them a value, with where the first such read is; and the names
    every path through the body assigns. An element of the routine's own `arrays` is
    read before it has a value where no element of that array was assigned before,
    on any path (element by element is not followed: a loop fills an array)."""
    reads: dict[str, object] = {}
    filled: set[str] = set()  # the arrays some element of which was assigned

    def read(expr, given: set[str]) -> None:
        for n in ast.walk(expr):
            if isinstance(n, ast.Name) and n.name not in given:
                reads.setdefault(n.name, n.span)
            elif isinstance(n, (ast.Call, ast.Index)):
                name = n.func if isinstance(n, ast.Call) else n.name
                if name in arrays and name not in filled:
                    reads.setdefault(name, n.span)

    def walk(statements, given: set[str]) -> set[str]:
        given = set(given)
        for st in statements:
            if isinstance(st, ast.Assign):
                for e in (st.expr, *st.subscripts):
                    read(e, given)
                given.update(st.targets)
                filled.update(t for t in st.targets if t in arrays)
            elif isinstance(st, ast.If):
                branch_given = []
                for b in st.branches:
                    if b.cond is not None:
                        read(b.cond, given)
                    branch_given.append(walk(b.body, given))
                if st.branches[-1].cond is None:  # (an ELSE: every path passes a branch)
                    given |= set.intersection(*branch_given)
            elif isinstance(st, ast.Loop):
                for e in (st.start, st.stop, st.step):
                    if e is not None:
                        read(e, given)
                inside = walk(st.body, given | {st.var})
                # (a loop of whole-number bounds that makes a pass assigns what its
                # body does; one that may make none, nothing)
                bounds = [e.value if isinstance(e, ast.Num) else None
                          for e in (st.start, st.stop, st.step or ast.Num(1.0, st.span))]
                if None not in bounds and bounds[2] != 0 and \
                        (bounds[1] - bounds[0]) * bounds[2] >= 0:
                    given |= inside
                given.add(st.var)
            elif isinstance(st, ast.Procedural):  # (a CALL of another routine)
                for n in st.inputs:
                    if n not in given:
                        reads.setdefault(n, st.span)
                given.update(st.outputs)
        return given

    everywhere = walk(body, set())
    return reads, everywhere
