"""What the outputs say in words: switching events, headings in the listing's
language, units, run labels. Every printout, plot and report reads them here.
"""

from __future__ import annotations

import locale
import os
import re
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # standard library only at import: the command line reads LANGUAGES
    from ..result import Run

# ------------------------------------------------------------- languages

# Every fixed word of a report, by language. Add a language by adding a column.
WORDS: dict[str, dict[str, str]] = {
    "en": {
        "listing": "Listing", "data": "Data and initial values",
        "equations": "Equations as evaluated", "run": "Run", "plots": "Plots",
        "events": "Switching events", "range": "Range", "terminal": "Final values (TERMINAL)",
        "partial": "Partial results", "model file": "Model file", "name": "name",
        "value": "value", "unit": "unit", "description": "description",
        "defined": "defined", "minimum": "minimum", "maximum": "maximum", "time": "time",
        "switch": "switch", "change": "change", "figure": "Figure", "more": "more",
        "printer plot": "Printer plot", "notes": "Notes", "line": "line",
        "against": "against", "around": "around",
        "partial report": "PARTIAL REPORT: a run failed; what it computed is shown",
        "accuracy": "Accuracy check",
        "acc digits": "{name}: {digits} significant digits stand with {how} (largest "
                      "difference {largest:.2e} at TIME {at:.6g})",
        "acc same": "{name}: the same to every digit with {how}",
        "acc numerical": "{name}: its variation of {half:.2e} either way is numerical: it "
                         "changes by {largest:.2e} (at TIME {at:.6g}) with {how}",
        "acc events same": "events: the same {n}, the largest shift {shift:.2e} s with {how}",
        "acc events differ": "events: {n} here, {m} with {how}: an event depends on the "
                             "tolerance",
        "acc not made": "accuracy check not made: {why}",
        "observed": "observed", "simulated": "simulated", "residual": "residual",
        "variable": "variable", "count": "n", "rms": "RMS residual",
        "largest": "max |residual|", "data vs run": "Observations against the run",
    },
    "pl": {
        "listing": "Listing programu", "data": "Dane i wartości początkowe",
        "equations": "Równania w kolejności obliczeń", "run": "Przebieg", "plots": "Wykresy",
        "events": "Przełączenia", "range": "Zakres zmienności",
        "terminal": "Wartości końcowe (TERMINAL)", "partial": "Wyniki częściowe",
        "model file": "Plik modelu", "name": "nazwa", "value": "wartość",
        "unit": "jednostka", "description": "opis", "defined": "definicja",
        "minimum": "minimum", "maximum": "maksimum", "time": "czas",
        "switch": "przełącznik", "change": "zmiana", "figure": "Rys.", "more": "więcej",
        "printer plot": "Wykres drukarkowy", "notes": "Uwagi", "line": "wiersz",
        "against": "w funkcji", "around": "wokół",
        "partial report": "RAPORT CZĘŚCIOWY: przebieg przerwany; pokazano to, co obliczono",
        "accuracy": "Sprawdzenie dokładności",
        "acc digits": "{name}: {digits} cyfr znaczących bez zmian przy {how} (największa "
                      "różnica {largest:.2e} dla TIME {at:.6g})",
        "acc same": "{name}: bez zmian przy {how}",
        "acc numerical": "{name}: zmienność ±{half:.2e} jest numeryczna: zmienia się o "
                         "{largest:.2e} (TIME {at:.6g}) przy {how}",
        "acc events same": "przełączenia: te same ({n}), największe przesunięcie {shift:.2e} s "
                           "przy {how}",
        "acc events differ": "przełączenia: {n} tutaj, {m} przy {how}: przełączenie zależy "
                             "od tolerancji",
        "acc not made": "sprawdzenia dokładności nie wykonano: {why}",
        "observed": "pomiar", "simulated": "symulacja", "residual": "różnica",
        "variable": "zmienna", "count": "n", "rms": "różnica RMS",
        "largest": "maks. |różnica|", "data vs run": "Pomiary a symulacja",
    },
}


def accuracy_lines(check, words: dict[str, str]) -> list[str]:
    """What an accuracy check (`run.accuracy.AccuracyCheck`) found, in words."""
    if check.message:
        return [words["acc not made"].format(why=check.message)]
    out = []
    for v in check.variables:
        key = "acc numerical" if v.numerical else "acc same" if v.largest == 0 else \
            "acc digits"
        out.append(words[key].format(name=v.name, digits=v.digits, how=check.how,
                                     largest=v.largest, at=v.at, half=v.variation / 2))
    if check.events != check.events_tight:
        out.append(words["acc events differ"].format(n=check.events, m=check.events_tight,
                                                     how=check.how))
    elif check.events:
        out.append(words["acc events same"].format(n=check.events, shift=check.shift,
                                                   how=check.how))
    return out
LANGUAGES = tuple(WORDS)

# Polish written without diacritics (as on a line printer) still has these words.
_POLISH_WORDS = frozenset("""CWICZENIE NAPED SILNIK SILNIKA PREDKOSC PREDKOSCI KATOWA KATOWE
MOMENT MOMENTU OBCIAZENIE OBCIAZENIA SPRZEGLO SPRZEGLA WAL WALU PRAD PRADU NAPIECIE
PRZEBIEG WIRNIK WIRNIKA TLUMIENIE SZTYWNOSC BEZWLADNOSCI UKLAD UKLADU SYMULACJA ORAZ
CZAS DLA PRZY""".split())
_POLISH_LETTERS = frozenset("ąćęłńóśźżĄĆĘŁŃÓŚŹŻ")


def detect_language(texts: Iterable[str], environ: dict[str, str] | None = None) -> str:
    """"pl" when the TITLE/LABEL text is Polish (its letters, or its common words
    written without them), else the locale's language if it is one of ours, else "en"."""
    joined = " ".join(texts)
    if any(ch in _POLISH_LETTERS for ch in joined):
        return "pl"
    if _POLISH_WORDS.intersection(re.findall(r"[A-Za-z]+", joined.upper())):
        return "pl"
    env = os.environ if environ is None else environ
    for key in ("LC_ALL", "LC_MESSAGES", "LANG"):
        if env.get(key):
            code = env[key].split("_")[0].split(".")[0].lower()
            return code if code in WORDS else "en"
    try:
        code = (locale.getlocale()[0] or "").split("_")[0].lower()
    except ValueError:
        code = ""
    return code if code in WORDS else "en"


# ------------------------------------------------------------- listing text

# control characters a listing may carry into a printout, a message, a figure or a
# report (ESC starts a terminal's escape sequences: clear the screen, retitle the
# window, ...): shown as "?"; amilpy's own output needs only the line ends, tabs and
# the progress line's \r
CONTROL = {c: "?" for c in [*range(0x20), 0x7F, *range(0x80, 0xA0)] if c not in (9, 10, 13)}


def visible(text: str) -> str:
    """`text` with its control characters shown as "?"."""
    return text.translate(CONTROL)


# ------------------------------------------------------------------ units

_BRACKET = re.compile(r"\[([^\[\]]+)\]")
# Unit symbols a lab sheet writes before a colon in a comment: "V*s/rad: ..." is a
# unit, "clutch: ..." is not.
_UNIT_WORDS = frozenset("""s ms us m mm cm km kg g n nm v mv a ma ohm h mh w kw j pa kpa
mpa bar rad deg rpm hz khz f uf k c l""".split())


def label_unit(label: str | None) -> str:
    """The unit a LABEL gives in brackets ("... [RAD/S]" -> "RAD/S"), or ""."""
    found = _BRACKET.findall(visible(label or ""))
    return found[-1].strip() if found else ""


def comment_fields(comment: str) -> tuple[str, str]:
    """A trailing `!` comment as (unit, description): `[V*s/rad] back-EMF` or
    `V*s/rad: back-EMF` give the unit V*s/rad; any other text is a description."""
    text = visible(comment).strip()
    m = re.match(r"\[([^\[\]]*)\]\s*(.*)$", text)
    if m:
        return m.group(1).strip(), m.group(2).strip()
    m = re.match(r"([^\s:]+):\s*(.*)$", text)
    if m and (not m.group(1).isalpha() or m.group(1).lower() in _UNIT_WORDS):
        return m.group(1), m.group(2).strip()
    return "", text


def line_comments(source: str) -> dict[int, str]:
    """line number -> the text after the line's `!` (a line with no `!` is absent).
    The listing has no strings, and TITLE/LABEL text stops at `!`, so the first `!`
    starts the comment."""
    out = {}
    for number, line in enumerate(source.splitlines(), start=1):
        if "!" in line and not line.lstrip().startswith("*"):
            out[number] = line.split("!", 1)[1]
    return out


def comments_by_name(source: str, lines: dict[str, int]) -> dict[str, tuple[str, str]]:
    """name -> (unit, description) from the trailing comment of the line defining it.
    A line defining several names shares its comment out by `;` when it has one part
    per name (`CONST U = 12.0, R = 13.7 ! [V] supply; [ohm] winding`)."""
    comments = line_comments(source)
    per_line: dict[int, list[str]] = {}
    for name, line in lines.items():
        per_line.setdefault(line, []).append(name)
    out = {}
    for line, names in per_line.items():
        if line not in comments:
            continue
        if len(names) == 1:
            out[names[0]] = comment_fields(comments[line])
            continue
        parts = comments[line].split(";")
        if len(parts) == len(names):
            for name, part in zip(names, parts, strict=True):
                out[name] = comment_fields(part)
    return out


# -------------------------------------------------------------- run labels


def changed_names(runs: Sequence[Run]) -> list[str]:
    """The data values that differ between the runs, in the order they appear."""
    names: list[str] = []
    for run in runs:
        for name in run.params:
            if name not in names and any(other.params.get(name) != run.params[name]
                                         for other in runs):
                names.append(name)
    return names


def run_column(names: Sequence[str]) -> str:
    """The name of a table's column of run numbers: RUN, or RUN# where one of the
    table's own columns is a listing's RUN (FST listings count their runs in a PARAM
    RUN: LINGRA's)."""
    return "RUN#" if "RUN" in names else "RUN"


def run_labels(runs: Sequence[Run]) -> list[str]:
    """What tells each run from the others: the data values that differ between
    them, run 1's included ("B = 6e-05", "B = 0.0002"); the run's own label when
    no data value differs (a TIMER change), or "" for a single run."""
    if len(runs) < 2:
        return [""] * len(runs)
    names = changed_names(runs)
    if not names:
        return [run.label or f"RUN {k}" for k, run in enumerate(runs, start=1)]
    return [", ".join(f"{n} = {run.params.get(n, float('nan')):g}" for n in names)
            for run in runs]


def run_heading(run: Run, index: int, label: str, words: dict[str, str]) -> str:
    """"Run 2: B = 0.0002"; "Run 1" for a run that only has its number."""
    own = label or ("" if re.fullmatch(r"RUN \d+", run.label) else run.label)
    return f"{words['run']} {index}" + (f": {own}" if own else "")


# ------------------------------------------------------------------- text


def shorten(text: str, limit: int) -> str:
    """At most `limit` characters, cut at a word with an ellipsis (for a plot title:
    the report and printout keep the whole text)."""
    text = " ".join(visible(text).split())
    if len(text) <= limit:
        return text
    cut = text[: limit - 1]
    if " " in cut[limit // 2:]:
        cut = cut[: cut.rindex(" ")]
    return cut.rstrip() + "…"



def name_notes(model) -> dict[str, tuple[str, str]]:
    """name -> (unit, description) of every value and variable whose defining line
    has a trailing `!` comment (`model` is an ir.Model); TIME's unit too: seconds in
    the CSMP form (the lab's mechanics), days in an FST listing (FSE's), none said
    in the ACSL form (a pharmacokinetic program counts hours)."""
    notes = comments_by_name(model.source, {n: s.line for n, s in model.spans.items()})
    if "TIME" not in notes:
        fst = (model.path or "").lower().endswith(".fst")
        notes["TIME"] = ("" if model.acsl is not None else "d" if fst else "s", "")
    return notes


def unit_of(names: Sequence[str], label: str | None,
            notes: dict[str, tuple[str, str]]) -> str:
    """The unit of an axis: the LABEL's bracket, else the unit the variables'
    comments give when they all give the same one."""
    unit = label_unit(label)
    if unit:
        return unit
    units = {notes.get(n, ("", ""))[0] for n in names}
    return units.pop() if len(units) == 1 else ""
