"""Measured data beside a run (`--data FILE`, `Model.run(data=...)`): a CSV of
observations read and checked against the listing, the instants the runs must
have rows at, and each run's comparison (`result.Compared`).

The file: a header line naming the columns, then one line per instant. Commas
between fields and a decimal point, or semicolons and a decimal comma (as
`--csv-dialect excel-pl` writes them); lines starting with `#` and blank lines
are skipped. Columns (case-insensitive):

- `TIME` (or `T`): the instant, required;
- a listing variable (`W2`): its observed values; an empty cell is no observation;
- `SD_<NAME>`: the standard deviation of each observation of NAME (optional);
- `RUN`: which run (1, 2, ... in the listing's order of PARAM lists and END
  groups) a line belongs to; without it every line belongs to every run.

The simulated value at an observation is the run's own value at that instant
(the instants are put among the run's rows, located like any other), never an
interpolation between rows. What a run cannot have a row at (an ACSL program's
rows are its communication instants; step-point mode's are its steps) is refused
with what to change."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .diagnostics import AmilError, Diagnostic, Span, did_you_mean
from .language import plain_float
from .result import Compared, Run, Status
from .run.plan import SAME_INSTANT, nearest_instants

TIME_COLUMNS = ("TIME", "T")
SD_PREFIX = "SD_"


@dataclass(frozen=True)
class Series:
    """The observations of one variable in one run (run None: every run)."""

    name: str
    run: int | None
    t: np.ndarray
    values: np.ndarray
    sd: np.ndarray | None
    lines: tuple[int, ...]  # the file's line of each observation (for messages) ...
    columns: tuple[int, ...] = ()  # ... the column of its TIME cell ...
    value_columns: tuple[int, ...] = ()  # ... and of its value


@dataclass(frozen=True)
class Observations:
    path: str
    source: str
    series: tuple[Series, ...]
    runs_column: bool  # the file has a RUN column

    def for_run(self, number: int) -> list[Series]:
        """The series that belong to run `number` (1-based)."""
        return [s for s in self.series if s.run is None or s.run == number]

    def times(self, number: int | None = None) -> np.ndarray:
        """Every observed instant of run `number` (None: of every run), sorted, each
        once."""
        parts = [s.t for s in (self.series if number is None else self.for_run(number))]
        return np.unique(np.concatenate(parts)) if parts else np.empty(0)

    def error(self, message: str, line: int, column: int = 1, hint: str | None = None,
              end: int | None = None) -> AmilError:
        return AmilError([Diagnostic(message, Span(line, column, line, end), hint)],
                         self.path, self.source)


def _fields(line: str, sep: str) -> list[tuple[str, int]]:
    """The fields of a line with the 1-based column each starts at."""
    out, start = [], 0
    for part in line.split(sep):
        lead = len(part) - len(part.lstrip())
        out.append((part.strip(), start + lead + 1))
        start += len(part) + 1
    return out


def read(path: str, variables, runs: int) -> Observations:
    """The observations in the CSV at `path` for a model with `variables` (names)
    and `runs` runs; an AmilError at the file's line and column for a column that
    names no variable, a cell that is not a finite number, a RUN out of range."""
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            source = fh.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise AmilError(f"cannot read the data file: {exc.strerror or exc}", path) from None
    bare = Observations(path, source, (), False)
    lines = [(k, text) for k, text in enumerate(source.splitlines(), start=1)
             if text.strip() and not text.lstrip().startswith("#")]
    if not lines:
        raise AmilError("the data file has no header line (TIME and the variables' "
                        "names)", path)
    head_line, head = lines[0]
    sep = ";" if ";" in head else "\t" if "\t" in head and "," not in head else ","
    decimal_comma = sep == ";"
    known = {v.upper() for v in variables}
    header = _fields(head, sep)
    names = [h.upper() for h, _ in header]
    time_col = next((k for k, n in enumerate(names) if n in TIME_COLUMNS), None)
    if time_col is None:
        raise bare.error("the data file has no TIME column", head_line, 1,
                         "name the column of instants TIME (or T) in the header line")
    kinds: dict[int, tuple[str, str]] = {}  # column -> ("value"|"sd"|"run", variable)
    for k, ((text, col), name) in enumerate(zip(header, names, strict=True)):
        if k == time_col:
            continue
        if not name:  # (a spreadsheet's trailing separator: a column nothing is in)
            kinds[k] = ("none", "")
        elif name == "RUN":
            kinds[k] = ("run", "")
        elif name.startswith(SD_PREFIX) and name[len(SD_PREFIX):] in known:
            kinds[k] = ("sd", name[len(SD_PREFIX):])
        elif name in known:
            if any(v == ("value", name) for v in kinds.values()):
                raise bare.error(f"column {text} appears twice", head_line, col,
                                 end=col + len(text))
            kinds[k] = ("value", name)
        else:
            close = did_you_mean(name.removeprefix(SD_PREFIX), sorted(known))
            raise bare.error(
                f"the column {text or '(empty)'!r} names no variable of the listing",
                head_line, col, close or "name each column after a variable of the "
                "listing (or SD_<NAME>, RUN)", end=col + max(len(text), 1))
    for kind, name in kinds.values():
        if kind == "sd" and ("value", name) not in kinds.values():
            raise bare.error(f"SD_{name} without a {name} column", head_line)
    rows: dict[tuple[int | None, str], list[tuple[float, float, float, int]]] = {}
    for number, text in lines[1:]:
        cells = _fields(text, sep)
        if len(cells) > len(header) and any(c for c, _ in cells[len(header):]):
            c, col = next((c, col) for c, col in cells[len(header):] if c)
            raise bare.error(f"more fields than the header's {len(header)}", number, col,
                             end=col + len(c))

        def value(k: int, cells=cells, number=number) -> float | None:
            return _cell(bare, cells, k, number, decimal_comma)
        t = value(time_col)
        if t is None:
            raise bare.error("no TIME on this line", number, 1)
        t_col = cells[time_col][1]
        for k, (kind, _) in kinds.items():
            if kind == "none" and k < len(cells) and cells[k][0]:
                raise bare.error("a value in a column with no name", number, cells[k][1],
                                 "name the column in the header line")
        run: int | None = None
        for k, (kind, _) in kinds.items():
            if kind == "run":
                r = value(k)
                if r is None or r != int(r) or not 1 <= r <= runs:
                    raise bare.error(f"RUN must be a run number from 1 to {runs}", number,
                                     cells[k][1] if k < len(cells) else 1)
                run = int(r)
        for k, (kind, name) in kinds.items():
            if kind != "value":
                continue
            x = value(k)
            if x is None:
                continue
            sd_col = next((j for j, v in kinds.items() if v == ("sd", name)), None)
            sd = value(sd_col) if sd_col is not None else None
            if sd_col is not None and (sd is None or not sd > 0):
                raise bare.error(f"SD_{name} must be a positive number where {name} is "
                                 "given", number, cells[sd_col][1] if sd_col < len(cells)
                                 else 1)
            rows.setdefault((run, name), []).append(
                (t, x, sd if sd is not None else math.nan, number, t_col, cells[k][1]))
    series = []
    for (run, name), points in rows.items():
        points.sort(key=lambda p: p[0])
        a = np.array([p[:3] for p in points], dtype=float)
        sd = a[:, 2] if np.all(np.isfinite(a[:, 2])) else None
        series.append(Series(name, run, a[:, 0], a[:, 1], sd, tuple(p[3] for p in points),
                             tuple(p[4] for p in points), tuple(p[5] for p in points)))
    if not series:
        raise bare.error("the data file has no observations", head_line, 1,
                         "put a line per instant under the header")
    return Observations(path, source, tuple(series), any(k == "run" for k, _ in
                                                         kinds.values()))


def _cell(obs: Observations, cells: list[tuple[str, int]], k: int, line: int,
          decimal_comma: bool) -> float | None:
    """Field k of a line as a number (None: empty); an error at it if it is none."""
    if k >= len(cells) or not cells[k][0]:
        return None
    cell, col = cells[k]
    x = _number(cell.replace(",", ".") if decimal_comma else cell)
    if x is None:
        raise obs.error(f"{cell!r} is not a number", line, col,
                        "write a number (" + ("decimal comma" if decimal_comma
                                              else "decimal point") + ")",
                        end=col + len(cell))
    return x


def _number(text: str) -> float | None:
    x = plain_float(text)
    return x if x is not None and math.isfinite(x) else None


def compare(run: Run, obs: Observations, number: int, why_no_row: str) -> list[Compared]:
    """Run `number`'s observations against its values at their instants. An
    instant the run reached without a row there is an error saying `why_no_row`;
    one past a failed run's end is left out (the comparison says how many)."""
    out = []
    times = run.times
    t0, t1 = float(times[0]), run.t_end
    finished = run.status == Status.FINISHED
    for s in obs.for_run(number):
        outside = s.t < t0 - SAME_INSTANT * max(1.0, abs(t0))
        if finished:
            outside |= s.t > t1 + SAME_INSTANT * max(1.0, abs(t1))
        if outside.any():
            k = int(np.argmax(outside))
            raise obs.error(f"TIME {s.t[k]:g} is outside run {number}, which goes from "
                            f"TIME {t0:g} to {t1:g}", s.lines[k], s.columns[k],
                            "leave out the observations the run does not reach, or "
                            "change FINTIM")
        if s.name not in run.values:
            continue  # (a variable the run does not record: none, checked before)
        pick, hit = nearest_instants(times, s.t)
        reached = np.ones(len(s.t), bool) if finished else \
            s.t <= t1 + SAME_INSTANT * max(1.0, abs(t1))
        missing = ~hit & reached
        if missing.any():
            k = int(np.argmax(missing))
            raise obs.error(f"run {number} has no row at TIME {s.t[k]:g}", s.lines[k],
                            s.columns[k], why_no_row)
        keep = hit & reached
        sim = run.values[s.name][pick[keep]]
        out.append(Compared(s.name, s.t[keep], s.values[keep], np.asarray(sim, float),
                            None if s.sd is None else s.sd[keep], obs.path,
                            int(np.count_nonzero(~reached))))
    return out
