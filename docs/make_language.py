"""Write docs/language.md, the language reference, from the registries.

The lists a reader looks things up in — keywords, methods, functions, what is refused —
are generated here from the modules that the parser, checker and runner read
(`amilpy.language`, `amilpy.routes`, `amilpy.library`), so the reference cannot
say what amilpy does not do. The prose around them is written below.
tests/test_docs_language.py fails when docs/language.md is not what this writes.

    python docs/make_language.py          # rewrite docs/language.md
    python docs/make_language.py --check  # exit 1 if it is out of date
"""

from __future__ import annotations

import sys
from pathlib import Path

from amilpy import language, library, routes
from amilpy.run.plan import TOLERANCES

OUT = Path(__file__).resolve().parent / "language.md"

INTRO = """\
# The amilpy language reference

amilpy reads listings of the CSSL family in three forms. The contract is
`../shared/amil-language.md` (sections 1-14); this page is the reference a user
looks things up in. Its tables are generated from the registries the parser,
checker and runner read (`python docs/make_language.py`), so they list exactly
what amilpy runs. The functions' fuller notes are in `docs/functions.md`; the
shipped models and what they are checked against in `docs/models.md`.

{forms}

Keywords and names are case-insensitive; `!` starts a comment (except in `!=`); a
line whose first character is `*` is a comment line; `...` or `&` at the end of a
line continues the statement on the next one; text after `STOP` is not read.
"""

FORM_ROWS: tuple[tuple[str, ...], ...] = (
    ("**CSMP form** (the lab's AMIL, CSMP III, CSMP/360, FST)", "the default", "`TIME`",
     "DYNAMIC is sorted; INITIAL and TERMINAL run in written order",
     "`models/ex4_clutch.amil`, `models/examples/csmp_diode_filter.amil`"),
    ("**ACSL form** (ACSL, Magnolia)", "the first statement is `PROGRAM` or `MODEL`",
     "`T` (and `TIME`)", "DERIVATIVE is sorted; INITIAL, DYNAMIC, DISCRETE, TERMINAL run "
     "in written order", "`models/examples/oral_dosing.csl`"),
    ("**FST form** (Wageningen's FORTRAN Simulation Translator)", "CSMP form with FST's "
     "statements (`TIMER STTIME`, `FINISH X > v`, `TRANSLATION_GENERAL`, `WEATHER`, `;` "
     "between items)", "`TIME` from `STTIME`", "as CSMP", "`models/examples/fst_wheat.fst`"),
)

# The side-by-side table: one row per construct whose spelling or meaning differs
# between the dialects. amilpy reads every left-hand spelling as written.
SIDE_BY_SIDE: tuple[tuple[str, str, str], ...] = (
    ("ACSL", "`X = INTEG(XD, X0)`", "`X = INTGRL(X0, XD)` (the arguments the other way round)"),
    ("CSMP III", "`X = INTGRL(X0, XD)`", "a state X with X(t0) = X0 and dX/dt = XD"),
    ("ACSL", "`T`", "`TIME` (in ACSL form; `TIME` is read too)"),
    ("ACSL", "`CONSTANT K = 2.0`", "`CONST K = 2.0`"),
    ("ACSL", "`CINTERVAL CINT = 0.1`", "rows every 0.1 (OUTDEL/PRDEL = CINT)"),
    ("ACSL", "`TERMT(T >= TSTOP, 'msg')`", "the run stops where the condition first holds, "
     "located like a switch; the message is printed"),
    ("ACSL", "`ALGORITHM IALG = 2`", "`METHOD " + routes.IALG_METHODS[2] + "` (the table of "
     "methods below gives every IALG)"),
    ("ACSL", "`MAXTERVAL MAXT = h`, `MINTERVAL MINT = h`", "`TIMER DELMAX = h`, "
     "`TIMER DELMIN = h`"),
    ("ACSL", "`MERROR X = 1E-6`, `XERROR X = 1E-9`", "`RELERR X = 1E-6`, `ABSERR X = 1E-9` "
     "(per state)"),
    ("ACSL", "`SCHEDULE D .AT. T + 1.0`", "DISCRETE section D runs at that instant"),
    ("ACSL", "`SCHEDULE D .XN. H`", "D runs where H crosses zero downwards, located"),
    ("ACSL", "`DISCRETE D` / `INTERVAL DT = 0.5`", "D runs every 0.5 from the start"),
    ("ACSL", "`IF (X .GT. 0.0) THEN ... ELSE ... END IF`", "in sorted code a switch on X, "
     "located; in written-order code a branch. An ELSE IF's test is read only where the "
     "tests before it are false, a test inside a THEN only where the THEN's is true, as "
     "Fortran reads them (`ELSE IF (LOG(X - 0.5) < -1.0)` after `IF (X <= 0.5)`)"),
    ("ACSL", "`CHARACTER MSG*80`, `CONSTANT MSG = 'text'`", "read and set aside: a run "
     "computes with numbers, so a CHARACTER name read in a computation is an error; a "
     "length (`CHARACTER*40`, `REAL*8`) is read and left"),
    ("ACSL", "`PROCEDURAL (Y = X) ... END`", "one sorted unit with outputs Y and inputs X, "
     "written order inside"),
    ("ACSL", "`IF (C) GO TO 10`, `GO TO P`, `10: X = 1.0`, `P: CONTINUE`", "a jump forward in "
     "written-order code (a PROCEDURAL, INITIAL, DISCRETE, TERMINAL), out of IF blocks and "
     "DO loops: written out as IF blocks with a flag per label (`GOk#10`, a variable of "
     "the section); refused: a jump back (a loop), into a block, in DERIVATIVE's sorted "
     "code"),
    ("ACSL", "`A .AND. B`, `A && B`, `X .NE. Y`, `X != Y`", "`A AND B`, `X /= Y`"),
    ("ACSL", "`PULSE(TZ, P, W)`, `HARM(TZ, W, P)`, `RSW(C, A, B)`, `BCKLSH(IC, DL, X)`",
     "a pulse train, `SINE(TZ, W, P)`, a switch on C, `HSTRSS(IC, -DL, DL, X)`"),
    ("ACSL", "`DELAY(X, IC, TDL, NMX)`", "`DELAY` with the value IC before t0 + TDL (TDL may "
     "change in time)"),
    ("ACSL", "`ALGORITHM IALG = 3` (Euler)", "`METHOD RECT` in step-point mode"),
    ("ACSL", "`DIMENSION X(3)`, `CONSTANT X = 1.0, 2*0.0`, `X[I]`, `FOR I = 1, 3 ... END`",
     "the elements `X(1)`, `X(2)`, `X(3)`, variables of their own (Arrays, below)"),
    ("ACSL", "`ARRAY X(3)` (acslX)", "`DIMENSION X(3)`"),
    ("ACSL", "`MACRO LAG(Y, X, TAU, Y0)` ... `MACRO END`, called `LAG(Z, U, 2.0, 0.0)` or "
     "`Z = LAG(U, 2.0, 0.0)`; `MACRO STANDVAL Y0 = 0.0`, `MACRO REDEFINE R`",
     "the body expanded at each call: an argument the body assigns is the call's variable, "
     "the others the call's expressions (whole), arguments left out at the end their "
     "STANDVAL values, REDEFINE's names each call's own, every other name the program's; "
     "MACRO RELABEL, IF, GO TO and EXIT are refused"),
    ("ACSL", "`DO 10 I = 1, N` ... `10 CONTINUE`, `DO L1 I = 1, N` ... `L1: CONTINUE`",
     "`DO I = 1, N ... END DO` (one label may end several loops)"),
    ("ACSL", "`TABLE F, 1, 3 / 0., 1., 2., 0., 1., 4. /`, `Y = F(X)`", "`FUNCTION F = 0.,0., "
     "1.,1., 2.,4.`, `Y = AFGEN(F, X)`: linear between the breakpoints, the end values "
     "outside; `TABLE G, 2, NX, NY / x..., y..., values (x fastest) /`, `G(X, Y)`: "
     "bilinear, and trilinear for 3 variables"),
    ("ACSL", "code after the program's final `END`", "not read, with a warning"),
    ("CSMP III", "`MACRO Y = LAG2(T, X) ... ENDMAC`, `A = LAG2(0.1, U)`", "the body "
     "expanded at each call (its own states and locals per call)"),
    ("CSMP III", "`PROCEDURE Y, Z = P(A, B) ... ENDPRO`", "`PROCEDURAL (Y, Z = A, B)`"),
    ("CSMP III", "`NOSORT ... SORT`", "a written-order unit inside sorted code"),
    ("CSMP III", "`Y = IMPL(Y0, P, FY)` ... `FY = ...`", "Y solved from Y = FY(Y) at every "
     "evaluation, to abs(FY - Y) <= P*max(1, abs(Y))"),
    ("FST", "`CALL GLA(TIME, ..., GLAI)` with `SUBROUTINE GLA(...)` ... `END` after STOP",
     "the subroutine run as a PROCEDURAL at the CALL: the arguments its body assigns are "
     "outputs (the CALL gives names there), the others inputs; its other names are its own. "
     "A subset of Fortran 77: fixed form, IMPLICIT REAL (A-Z) or NONE, REAL, INTEGER, "
     "LOGICAL and "
     "DIMENSION declarations, the routine's own arrays of one subscript with DATA, "
     "PARAMETER, assignments, logical, arithmetic (`IF (E) 10, 20, 30`, forward) and "
     "block IFs, DO loops (labelled, with CONTINUE, or "
     "DO ... END DO), CALLs of the other routines after STOP, FUNCTION subprograms "
     "(`REAL FUNCTION F(X)` ... `F = ...` ... `END`: a reference F(X), in the listing or a "
     "routine, runs it first, as a CALL with F's value its last argument), SAVE (and a "
     "DATA value the routine changes: kept as below, DATA's value, else 0, at first, "
     "and at each rerun), "
     "GO TO forward to a labelled statement (as the "
     "ACSL form's), RETURN at the end, TTUTIL's `CALL FATALERR(MODULE, MESSAGE)` (with "
     "`CHARACTER*20 M` texts given once in quotes for it) and STOP or STOP 'text' (the run "
     "stops there, as at a "
     "TERMT, saying the text: SUCROS's ASTRO checks its latitude so; it is reached as "
     "Fortran reaches it, in an ELSE, a DO loop or after a GO TO, and ends the program: "
     "no later run is made), array arguments "
     "(`REAL MNDAT(NH)`: the CALL gives an ARRAY's name). A variable the routine changes "
     "from the value it had (`INCUT = INCUT + 1.`, or one it sets on some paths only, or "
     "a name of its own it keeps) is "
     "Fortran's by reference, as FSE runs the generated code: after the CALL the listing "
     "reads the new value; before it, the value is the one the routine left at the last "
     "step point (a PARAM's own at first, the listing's name then the changed value "
     "everywhere; once per step point, so step-point mode only), "
     "or a weather variable's of the day (PENMAN's `VP = MIN(VP, SVP)`). Refused at "
     "their line: a GO TO back or computed, COMMON, "
     "LOGICAL arrays, CHARACTER other than FATALERR's texts, an INTEGER given a value "
     "that is no whole number or divided "
     "by one (Fortran cuts both), an array's DATA values the routine changes, a kept name "
     "in a routine another routine CALLs, "
     "recursion; and a "
     "name given both as a value it reads and as an argument it assigns. The rest of the "
     "text after STOP is not read"),
    ("FST", "`ARRAY MNDAT(1:NH)`, `ARRAY_SIZE NH = 10`, `PARAM MNDAT(1) = 135.; "
     "MNDAT(6:NH) = 999.`", "an array of NH elements, each a variable of its own "
     "(`MNDAT(1)` ...; the sizes are fixed when the listing is read); a range of elements "
     "is given one value for all or one each (`X(1:3) = 1., 2., 3.`); the whole array "
     "passed to a routine by its name"),
    ("FST, ACSL", "`PI = 3.1416` in a listing with FST's statements (WEATHER, "
     "TRANSLATION_GENERAL, DEFINE_CALL, EVENT, SET), or `CONSTANT PI = 3.141592` (or PI "
     "assigned in INITIAL) in an ACSL program", "the listing's own PI (neither language "
     "has one): a variable of the listing (or a PARAM, a CONSTANT), read, printed and set "
     "as any. Elsewhere PI is reserved (pi where a listing reads it)"),
    ("FST", "`EVENT` / `ZEROCONDITION E` / `NEWVALUE X = e` ... / `ENDEVENT`",
     "a state event: where E reaches zero from either side (located; in step-point mode "
     "at the first step point where it has, before that point's row) the NEWVALUEs are "
     "computed from the values before the event and given at once; X is a state or a "
     "SET variable. The EVENT may also hold assignments (values of its own, computed "
     "first) and PARAMETERs (the listing's)"),
    ("FST", "`EVENT` / `FIRSTTIME t1` / `NEXTTIME t2` / `NEWVALUE X = e` / `ENDEVENT`",
     "a time event: at t1 (a value before the run: `STTIME + 30.`), then at each t2 it "
     "gives there (`TIME + 30.`); the integration stops at each instant (in step-point "
     "mode: the first step point at or after it)"),
    ("FST", "`SET EMERG = 0.` in INITIAL", "EMERG's first value; afterwards it changes "
     "only where an EVENT's NEWVALUE sets it (kept between events, like a state)"),
    ("CSMP III, FST", "`ENDJOB`, the job's last statement", "the end of the runs, as "
     "`STOP`: the text after it is not read"),
    ("CSMP III", "`FIXED I, J`", "`INTEGER I, J`"),
    ("CSMP III", "`FINISH X = 10.0`", "the run stops where X crosses 10, located"),
    ("CSMP III", "`METHOD RECT`, `TIMER DELT = 0.1`", "Euler in step-point mode, the classic "
     "translators' loop, row for row"),
    ("FST", "`PARAM A = 1.; B = 2.`", "`PARAM A = 1., B = 2.` (`;` separates items)"),
    ("FST", "`TIMER STTIME = 80.; FINTIM = 300.`", "time runs from 80 to 300 (FINTIM is an "
     "end time)"),
    ("FST", "`FINISH DVS > 2.`", "the run stops where DVS first exceeds 2, located"),
    ("FST", "`TRANSLATION_GENERAL DRIVER = 'EUDRIV'`", "`METHOD RECT` in step-point mode; "
     "'RKDRIV' is `METHOD RKS`"),
    ("FST", "`WEATHER CNTR = 'NLD'; ISTN = 1; IYEAR = 1990`", "RDD, TMMN, TMMX, VP, WN, RAIN, "
     "DOY, ... read from the CABO file NLD1.990"),
    ("CSMP, FST", "`X = FSW(E, A, B, C)`, `INSW(E, A, B)`", "switches on E, every change of "
     "branch located (not stepped over)"),
    ("all", "`F = MT*SIGN(1.0, W)`, `ABS(X)`, `AMAX1(A, B, C)`, `AINT(X)`, `A > B`",
     "in sorted code switches like FSW: kinks and jumps located, dry friction at rest "
     "slides (`docs/functions.md`); in INITIAL, TERMINAL and written-order code their "
     "plain Fortran values"),
)

FORMS = """\
## The CSMP form

```
TITLE  MASS ON A SPRING
PARAM  K = 4.0, M = 1.0            ! values a run may change (--set K=5, value lists)
CONST  X0 = 1.0                    ! values fixed for every run
INITIAL
   W = SQRT(K/M)                   ! computed once, before the run
DYNAMIC
   X = INTGRL(X0, V)               ! the states: INTGRL(initial value, derivative)
   V = INTGRL(0.0, -K/M*X)
TIMER  FINTIM = 10.0, OUTDEL = 0.01, PRDEL = 0.5
METHOD AUTO
PRINT  X, V
OUTPUT X
END
STOP
```

DYNAMIC statements may be written in any order: amilpy sorts them (an algebraic
loop is an error naming its variables). A listing may hold several runs: after
`END`, new data values and `END` again; a value list `PARAM K = (1.0, 4.0)` makes
one run per value. `amilpy check` lists what it read.

## The ACSL form

```
PROGRAM  one-compartment model, repeated doses
  CONSTANT KE = 0.2, V = 10.0, DOSE = 100.0, TAU = 8.0, TSTOP = 48.0
  CINTERVAL CINT = 0.5
  INITIAL
    A = 0.0
  END
  DERIVATIVE
    A = INTEG(-KE*A, 0.0)
    C = A/V
    TERMT(T >= TSTOP, 'end of the regimen')
  END
  DISCRETE DOSING
    INTERVAL TAU = 8.0
    A = A + DOSE
  END
END
```

`END` closes the innermost block. INITIAL runs once at the start; DERIVATIVE is
sorted and integrated; DYNAMIC runs in written order at every CINT row; DISCRETE
sections run when SCHEDULE or INTERVAL says, and may change states (the run
restarts from the new values); TERMINAL runs once at the end. With no PRINT or
OUTPUT, every state is printed.

### Arrays

```
PROGRAM  three decays, one array
  DIMENSION X(3), XD(3), K(3), X0(3)
  CONSTANT K = 1.0, 2.0, 3.0, X0 = 3*1.0
  CINTERVAL CINT = 0.1
  DERIVATIVE
    PROCEDURAL (XD = X)
      DO I = 1, 3
        XD(I) = -K(I)*X(I)
      END DO
    END
    X = INTEG(XD, X0)
    TERMT(T >= 1.0)
  END
END
```

`DIMENSION X(3), A[2, 2]` (or a type: `REAL V(5)`, `DIMENSION INTEGER N(2)`) declares
arrays; `CONSTANT K = 1.0, 2.0, 3.0` gives their values in Fortran's order (the first
subscript fastest; `3*1.0` repeats). Each element is a variable of its own, named
`X(1)`, `A(2,1)` in the printout, the CSV and `--set`: sorting, the states, the
Jacobian and every METHOD see scalars. A subscript known when the listing is read
(numbers, constants, the variable of a loop over known bounds, which is written out
pass by pass) names its element; one known only as the run goes (`DOSE[DAY]` in a
DISCRETE section) reads through `ELEMENT(K, X1, ...)`, and a subscript outside the
array stops the run with its value. `X = INTEG(XD, X0)` and any statement that
assigns a whole array hold for each element; `PRINT X` lists the elements. The
constants that size an array or bound a written-out loop are fixed when the listing
is read: `--set` may not change them. A value or a repeat count in a CONSTANT list
may name a constant given a number before, as Fortran's DATA takes a PARAMETER
(`PARAMETER (NH = 3)` ... `CONSTANT F = NH*0.0`; it is fixed too), and a list shorter
than its array leaves the other elements 0, with a warning (the translators' static
storage; published tables rely on it). A CONSTANT inside a PROCEDURAL or an IF is a
declaration like any other.

### MACRO

```
MACRO LAG(Y, X, TAU, Y0)
  MACRO STANDVAL Y0 = 0.0
  MACRO REDEFINE RATE
  RATE = (X - Y)/TAU
  Y = INTEG(RATE, Y0)
MACRO END
PROGRAM  two lags in series
  CONSTANT U = 1.0, TAU = 2.0
  CINTERVAL CINT = 0.5
  DERIVATIVE
    Z = LAG(U, TAU)
    LAG(W, Z, TAU)
    TERMT(T >= 4.0)
  END
END
```

`MACRO NAME(A1, A2, ...) ... MACRO END` (before the PROGRAM or anywhere in it) is
written out at each call: `LAG(W, Z, TAU)` as a statement, or `Z = LAG(U, TAU)`, whose
names before `=` are the first arguments. An argument the body assigns must be given a
name; any other stands for the call's expression as a whole, and one the body reads as
an array or a table (`V(I)`, `F(X)`) for the call's array or table. `MACRO STANDVAL`
gives the arguments left out at the end; the names `MACRO REDEFINE` lists are each
call's own (`LAG#1.RATE`, `LAG#2.RATE` in the printout); every other name of the body is
the program's. ACSL's other MACRO directives (RELABEL, IF, GO TO, EXIT) are refused.

## The FST form

FST listings are CSMP-form listings with FST's statements: `;` between the items of
PARAM/INCON/TIMER/FINISH lines, `TIMER STTIME`, relational FINISH conditions,
`TRANSLATION_GENERAL DRIVER = 'EUDRIV'` (Euler in step-point mode, as FST runs it)
and `WEATHER`, whose daily variables are read from CABO-format files (the file
`NLD1.990` for `CNTR = 'NLD'; ISTN = 1; IYEAR = 1990`, looked for in WTRDIR, the
listing's folder, its `weather/` and `../weather/`, and `--weather-dir`). A `CALL`
of a Fortran subroutine written after STOP runs it, in a subset of Fortran 77 (the
FST row of the table below says which); one of no subroutine there is refused.
FST 3's events run as FSE runs them: `SET EMERG = 0.` in INITIAL gives a variable its
first value, and an `EVENT ... ENDEVENT` block gives new values to states and such
variables where its `ZEROCONDITION` reaches zero (LINTUL2-Cassava's emergence:
`ZEROCONDITION 1. - EMERGFAVOURABLE`, a condition that jumps from 1 to 0), or at the
instants `FIRSTTIME` and `NEXTTIME` give (LINTUL-banana's pruning every 30 days).
Fortran's `STOP 'text'` in a routine after STOP ends the run there, saying the text.
"""


def _table(head: tuple[str, ...], rows) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def _spellings(mapping: dict[str, str]) -> list[tuple[str, str]]:
    by: dict[str, list[str]] = {}
    for spelling, canon in mapping.items():
        by.setdefault(canon, []).append(spelling)
    return [(canon, ", ".join(f"`{s}`" for s in spellings)) for canon, spellings in by.items()]


def keywords() -> str:
    rows = [("section", ", ".join(f"`{s}`" for s in language.SECTIONS)
             + "; ACSL form: " + ", ".join(f"`{h}`" for h in language.ACSL_HEADS)
             + ", `INITIAL`, `DERIVATIVE`, `DYNAMIC`, `DISCRETE`, `TERMINAL` ... `END`")]
    rows += [("data: " + canon, spellings) for canon, spellings
             in _spellings(language.DATA_KEYWORDS)]
    rows += [("output: " + canon, spellings) for canon, spellings
             in _spellings(language.REPORT_KEYWORDS)]
    rows.append(("TIMER keys", ", ".join(f"`{k}`" for k in language.TIMER_KEYS)))
    (rel, ab), (arel, aab) = TOLERANCES["csmp"], TOLERANCES["acsl"]
    rows.append(("tolerances", ", ".join(f"`{k}`" for k in language.TOLERANCE_KEYWORDS)
                 + f" (one value, or per state: `RELERR X = 1E-6`); when a listing gives "
                 f"none, RELERR {rel:.0E}, ABSERR {ab:.0E} (ACSL form: {arel:.0E}, "
                 f"{aab:.0E}): every printed digit right"))
    rows.append(("ACSL integration control", ", ".join(
        f"`{k}`" for k in language.CONTROL_KEYWORDS)))
    rows.append(("declarations", ", ".join(f"`{k}`" for k in language.TYPE_KEYWORDS)))
    rows.append(("read-only names", ", ".join(f"`{k}`" for k in language.RESERVED)
                 + f"; `{language.ACSL_TIME}` in ACSL form; `{language.SEED_NAME}` seeds "
                 "the random functions"))
    return "## Statements\n\n" + _table(("what", "spellings"), rows)


def side_by_side() -> str:
    return ("## You wrote → amilpy reads it as\n\n"
            + _table(("dialect", "you wrote", "amilpy reads it as"), SIDE_BY_SIDE))


def methods() -> str:
    ialg: dict[str, list[str]] = {}
    for n, m in sorted(routes.IALG_METHODS.items()):
        ialg.setdefault(routes.METHODS[m].name, []).append(str(n))
    rows = [(", ".join(f"`{a}`" for a in r.aliases), r.summary,
             "DELT" if r.fixed else "RELERR, ABSERR", ", ".join(ialg.get(r.name, [])) or "-")
            for r in routes.ROUTES]
    return (f"## Methods (`METHOD`; default `{routes.DEFAULT}`)\n\n"
            + _table(("METHOD", "what it is", "step set by", "ACSL IALG"), rows))


_KINDS = {"MATH": "arithmetic",
          "NONSMOOTH": "arithmetic with kinks and jumps (switches in sorted code)",
          "STATE": "integrators (each call is a state)",
          "SWITCH": "switches (every change of branch located)",
          "TIME": "functions of time (their instants are breakpoints)",
          "IMPULSE": "impulses", "MEMORY": "functions with memory",
          "TABLE": "tables (`FUNCTION F = x1, y1, x2, y2, ...`)"}


def functions() -> str:
    groups: dict[str, list[tuple[str, str, str]]] = {}
    for f in library.FUNCTIONS.values():
        if f.name.startswith("."):
            continue  # the relational operators' switches, written A .GT. B
        for form in (f, *f.variants):
            doc = (form.doc or "").replace("|", "\\|")
            # the non-smooth arithmetic (ABS, SIGN, AMAX1, ...) apart from FSW and LIMIT
            kind = "NONSMOOTH" if f.kind is library.Kind.SWITCH and f.plain else f.kind.name
            groups.setdefault(kind, []).append(
                (f"`{form.signature}`", ", ".join(f"`{a}`" for a in f.aliases) or "", doc))
    parts = ["## Functions\n\nEvery function amilpy runs, by kind (one entry each in "
             "`amilpy/library/`). A call with the wrong arguments is answered with the "
             "signature below."]
    for kind, title in _KINDS.items():
        if kind in groups:
            parts.append(f"### {title.capitalize()}\n\n"
                         + _table(("call", "also spelled", "value"), groups[kind]))
    return "\n\n".join(parts)


def refused() -> str:
    rows = [(f"`{k}`", what, instead) for k, (what, instead) in language.REFUSED.items()]
    rows += [(f"`{k}(...)`", what, instead)
             for k, (what, instead) in language.REFUSED_FUNCTIONS.items()]
    return ("## What amilpy refuses\n\nThese constructs of the dialects are not run; a "
            "listing that uses one gets an error naming it, its line, and what to write "
            "instead (never a bare \"unexpected token\").\n\n"
            + _table(("keyword", "the construct", "write instead"), rows))


def render() -> str:
    intro = INTRO.format(forms=_table(("form", "how amilpy knows it", "time", "sorted",
                                       "example"), FORM_ROWS))
    return "\n\n".join([intro.rstrip(), FORMS.rstrip(), keywords(), side_by_side(),
                        methods(), functions(), refused()]) + "\n"


def main(argv: list[str]) -> int:
    text = render()
    if "--check" in argv:
        if OUT.read_text("utf-8") != text:
            print(f"{OUT} is out of date: run python docs/make_language.py")
            return 1
        return 0
    OUT.write_text(text, "utf-8")
    print(f"written: {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
