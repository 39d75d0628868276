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
                             "PI")
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

# What a line is, for the reader and for every message that quotes one: a line
# ends at \n, \r\n or \r, and nowhere else (not at U+2028, U+0085, a form feed
# or a vertical tab, where str.splitlines would also break).
LINE_BREAK = re.compile(r"\r\n|\r|\n")


def split_lines(text: str) -> list[str]:
    """The lines of a listing, numbered as diagnostics and the parser number them."""
    return LINE_BREAK.split(text)
