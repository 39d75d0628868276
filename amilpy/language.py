"""The language's vocabulary: reserved names, TIMER keys, section words and the
spellings each keyword accepts. Every stage that needs one of these lists reads
it here (parser, checker, runner, highlighter, docs), so they cannot drift.

Nothing here imports anything heavier than the standard library: `amilpy check`
and the highlighter read it at start-up.
"""

from __future__ import annotations

import re

# Read-only names a listing may use in expressions and never assign.
TIMER_KEYS: tuple[str, ...] = ("FINTIM", "DELT", "PRDEL", "OUTDEL", "DELMIN", "DELMAX")
TIME = "TIME"
RESERVED: tuple[str, ...] = (TIME, *("DELT", "DELMIN", "DELMAX", "FINTIM", "PRDEL", "OUTDEL"),
                             "STTIME", "PI")  # (STTIME: FST's start, 0 where none is given)
# Reserved names an INITIAL statement or an initial value may read (TIME is t0).
KNOWN_BEFORE_RUN: frozenset[str] = frozenset(RESERVED)
# Reserved names that are settings, not quantities: never a column of a printout.
SETTINGS: frozenset[str] = frozenset(set(RESERVED) - {TIME})

# The data value that seeds the random streams (GAUSS, UNIF, OU, ...) when the run is
# not given a seed (--seed, seed=): ACSL's system variable of that name. Default 1.
SEED_NAME = "RNSEED"

# Sections of the CSMP form, with the spellings that open them.
SECTIONS: dict[str, str] = {
    "INITIAL": "INITIAL",
    "DYNAMIC": "DYNAMIC",
    "DERIVATIVE": "DYNAMIC",
    "TERMINAL": "TERMINAL",
}

# Data statements: spelling -> canonical keyword.
DATA_KEYWORDS: dict[str, str] = {
    "PARAM": "PARAM",
    "PARAMETER": "PARAM",
    "CONST": "CONST",
    "CONSTANT": "CONST",
    "INCON": "INCON",
}

# Output statements: spelling -> canonical kind (PLOT is OUTPUT; PRTPLT is an
# OUTPUT figure that also draws a line-printer plot in the printout).
REPORT_KEYWORDS: dict[str, str] = {
    "PRINT": "PRINT",
    "OUTPUT": "OUTPUT",
    "PLOT": "OUTPUT",
    "PRTPLT": "PRTPLT",
    "RANGE": "RANGE",
    "PREPARE": "PREPARE",
}

TOLERANCE_KEYWORDS: tuple[str, ...] = ("RELERR", "ABSERR")

# FST's TIMER (section 13): STTIME is the start time (FINTIM then an end time); these
# other keys of FST's TIMER are read and have no meaning here.
START_KEY = "STTIME"
IGNORED_TIMER_KEYS: tuple[str, ...] = ("IPFORM", "COPINF", "DELTMP", "IDTMP")
# TRANSLATION_GENERAL DRIVER = '...' -> (METHOD, step-point mode or None: the method's)
DRIVERS: dict[str, tuple[str, bool | None]] = {"EUDRIV": ("RECT", True),
                                                "RKDRIV": ("RKS", None)}
# its other keys: what each becomes (None: read and ignored)
TRANSLATION_KEYS: dict[str, str | None] = {"DRIVER": "METHOD", "EPS": "RELERR",
                                           "DELMAX": "DELMAX", "TRACE": None}
TRANSLATION_FSE_DRIVER = "EUDRIV"  # TRANSLATION_FSE is FST's Euler translator
# WEATHER items (section 13) -> what they give the weather reader
WEATHER_KEYS: tuple[str, ...] = ("WTRDIR", "CNTR", "ISTN", "IYEAR")

# What a line is, for the reader and for every message that quotes one: a line
# ends at \n, \r\n or \r, and nowhere else (not at U+2028, U+0085, a form feed
# or a vertical tab, where str.splitlines would also break).
LINE_BREAK = re.compile(r"\r\n|\r|\n")


_NAME_OR_ELEMENT = re.compile(r"[A-Za-z][A-Za-z0-9_]*(?:\([0-9]+(?:,[0-9]+){0,2}\))?")


def given_name(text: str) -> str | None:
    """A variable's name as a command line or a call gives it, folded as a listing's
    (`k` -> `K`), an array's element too (`X( 2 )` -> `X(2)`, parse/arrays.py); None if
    the text is no name."""
    name = text.strip().replace(" ", "").upper()
    return name if _NAME_OR_ELEMENT.fullmatch(name) else None


def fortran_float(text: str) -> float:
    """A number as listings and command lines write it, Fortran's D exponent
    (1.5D-3) read as E; ValueError if the text is not a number."""
    return float(text.replace("D", "E").replace("d", "e"))


def plain_float(text: str) -> float | None:
    """The number `float` reads in the text (nan and inf too), or None."""
    try:
        return float(text)
    except ValueError:
        return None


def split_lines(text: str) -> list[str]:
    """The lines of a listing, numbered as diagnostics and the parser number them."""
    return LINE_BREAK.split(text)


# ------------------------------------------------ the ACSL form (contract 8-14)

# Statements whose items `;` separates like `,` (section 8); TRANSLATION_* too.
ITEM_KEYWORDS: frozenset[str] = frozenset({"PARAM", "PARAMETER", "CONST", "CONSTANT", "INCON",
                                           "TIMER", "FINISH", "WEATHER", "ARRAY",
                                           "ARRAY_SIZE"})
# A file whose first statement is one of these is in ACSL form (section 9).
ACSL_HEADS: tuple[str, ...] = ("PROGRAM", "MODEL")
ACSL_TIME = "T"  # time in ACSL form (TIME too, unless the listing assigns it)
DEFAULT_CINT = 0.1
MAX_LOOP = 1_000_000  # iterations of one FOR/DO loop
# elements of the arrays of one listing (each is a variable of its own), and the
# statements loops over arrays may be written out into
MAX_ELEMENTS = 200_000
MAX_INTERVALS = 1_000_000  # output intervals of a run no TERMT or FINTIM bounds
# ALGORITHM ... XERROR: integration control (section 11); the names are constants
CONTROL_KEYWORDS: tuple[str, ...] = ("ALGORITHM", "NSTEPS", "MAXTERVAL", "MINTERVAL",
                                     "MERROR", "XERROR")
# type statements -> what they store (double precision arithmetic throughout)
TYPE_KEYWORDS: dict[str, str] = {"LOGICAL": "LOGICAL", "INTEGER": "INTEGER", "REAL": "REAL",
                                 "DOUBLEPRECISION": "REAL", "DIMENSION": "REAL",
                                 "FIXED": "INTEGER",  # CSMP III's FIXED (section 13)
                                 # a text a CONSTANT gives, read by nothing that computes
                                 "CHARACTER": "CHARACTER"}

# Every statement keyword of the three forms, as the highlighter and the editors'
# grammars show them (grammar/amil.lark is the parser's own list); TITLE, LABEL and
# the section words are apart.
BLOCK_KEYWORDS: tuple[str, ...] = (
    "IF", "THEN", "ELSE", "ELSEIF", "ENDIF", "DO", "ENDDO", "FOR", "PROCEDURAL",
    "DISCRETE", "MACRO", "ENDMAC", "PROCEDURE", "ENDPRO", "NOSORT", "SORT", "EVENT",
    "ENDEVENT")
STATEMENT_KEYWORDS: tuple[str, ...] = (
    *DATA_KEYWORDS, "FUNCTION", "TIMER", "METHOD", *TOLERANCE_KEYWORDS, "FINISH", "TERMT",
    *REPORT_KEYWORDS, *ACSL_HEADS, "SCHEDULE", "INTERVAL", "CINTERVAL", "VARIABLE",
    *CONTROL_KEYWORDS, *(k for k in TYPE_KEYWORDS if k != "DOUBLEPRECISION"), "DOUBLE",
    "PRECISION", "WEATHER", "TRANSLATION_GENERAL", "TRANSLATION_FSE", "DEFINE_CALL",
    "DEFINE_FUNCTION",
    "ZEROCONDITION", "FIRSTTIME", "NEXTTIME", "NEWVALUE", "SET", *BLOCK_KEYWORDS)

# What amilpy does not run (section 14): the construct as a reader knows it, and what
# to write instead. Statement keywords first, then functions.
REFUSED: dict[str, tuple[str, str]] = {
    "GOTO": ("GO TO outside the ACSL form", "write IF (c) THEN ... ELSE ... END IF"),
    "CONTINUE": ("CONTINUE (the end of a labelled DO)", "write DO i = a, b ... END DO"),
    "ARRAY": ("an ARRAY statement not of FST's form X(1:N) (or, in ACSL form, X(N))",
              "write ARRAY X(1:N), Y(1:3) with ARRAY_SIZE N = 10"),
    "ARRAY_SIZE": ("an ARRAY_SIZE statement not of the form N = 10, M = 3",
                   "write ARRAY_SIZE N = 10"),
    "STORAGE": ("CSMP's STORAGE (arrays)", "write one scalar per element (X1, X2, ...)"),
    "TABLE": ("the TABLE statement", "write a table as FUNCTION F = x1,y1, x2,y2, ... and "
              "read it with AFGEN(F, X)"),
    "SUBMODEL": ("ACSL's SUBMODEL", "write the statements out"),
    "SUBROUTINE": ("a Fortran subroutine", "rewrite it as statements or a PROCEDURE; text "
                   "after STOP is not read"),
    "COMMON": ("Fortran COMMON", "remove it: every name of a listing is global"),
    "EQUIVALENCE": ("Fortran EQUIVALENCE", "remove it: write X = Y"),
    "EXTERNAL": ("Fortran EXTERNAL", "remove it"),
    "DATA": ("the Fortran DATA statement", "write CONSTANT X = value"),
    "READ": ("Fortran READ", "give the values with CONSTANT (or PARAM)"),
    "WRITE": ("Fortran WRITE", "name the variables in PRINT or OUTPUT"),
    "FORMAT": ("Fortran FORMAT", "remove it: PRINT and OUTPUT format the values"),
    "RETURN": ("Fortran RETURN", "write IF (c) THEN ... END IF around what it skips"),
    "INCLUDE": ("INCLUDE", "copy the included statements into the listing"),
}
REFUSED_FUNCTIONS: dict[str, tuple[str, str]] = {
    "IMPLC": ("ACSL's IMPLC (implicit algebraic loop)", "write the loop out with a state, "
              "e.g. a fast first-order lag REALPL"),
    "IMPVC": ("ACSL's IMPVC (vector implicit loop)", "write one state per element"),
    "INTVC": ("ACSL's INTVC (vector integration)", "write one INTEG per element"),
    "TRAN": ("ACSL's TRAN (transfer function)", "write it as INTEG states, or LEDLAG/"
             "REALPL/CMPXPL for first and second order"),
    "DBLINT": ("ACSL's DBLINT (double integrator with limits)", "write two INTEGs and "
               "an IF on the limits"),
}
