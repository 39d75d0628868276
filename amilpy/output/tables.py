"""The tables of a run, built once and rendered by every format.

A `Table` is columns of raw values with a format each; the printout, the
Markdown, LaTeX and PDF reports and the notebook view render the same `Table`
(see `text_blocks` here for the fixed-width form, and the report modules for the
others). Columns are read in slices, so a table of a million rows is rendered
row block by row block, never copied whole.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..result import Run

WIDTH = 14  # the lab printout's column width
COLUMNS_PER_BLOCK = 7  # value columns side by side in the printout
CHUNK = 1024  # rows formatted at a time


class _Take:
    """`source[index]`, taken a slice at a time (no copy of the whole column)."""

    def __init__(self, source: np.ndarray, index: np.ndarray) -> None:
        self.source, self.index = source, index

    def __len__(self) -> int:
        return len(self.index)

    def __getitem__(self, part: slice):
        return self.source[self.index[part]]


class _Repeat:
    """One value on every row (a constant PRINTed, or NaN for an unknown name)."""

    def __init__(self, value: float, n: int) -> None:
        self.value, self.n = value, n

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, part: slice):
        return [self.value] * len(range(*part.indices(self.n)))


@dataclass(frozen=True)
class Column:
    name: str
    values: Sequence  # anything sliceable: a list, an array, a _Take
    fmt: str = "e"  # e: 1.234560E+00, t: an instant to 9 digits, g: 6 digits, s: text
    unit: str = ""
    left: bool = False  # text reads from the left


@dataclass
class Table:
    key: str  # "printout", "range", "events", "terminal", "data"
    columns: list[Column]
    caption: str = ""
    notes: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.columns[0].values) if self.columns else 0

    def rows(self, columns: Sequence[Column] | None = None) -> Iterator[list[str]]:
        """The formatted cells, row by row, a block of rows at a time."""
        for block in self.blocks(columns):
            yield from (list(r) for r in zip(*block, strict=True))

    def blocks(self, columns: Sequence[Column] | None = None) -> Iterator[list[list[str]]]:
        """The formatted cells a block of CHUNK rows at a time, column by column."""
        columns = self.columns if columns is None else columns
        n = len(self)
        for start in range(0, n, CHUNK):
            part = slice(start, min(start + CHUNK, n))
            yield [cells(c.fmt, c.values[part]) for c in columns]


def values_of(chunk) -> list:
    return chunk.tolist() if isinstance(chunk, np.ndarray) else list(chunk)


_SPECS = {"e": ".6E", "t": ".9g", "g": ".6g"}


def cells(fmt: str, chunk, width: int = 0) -> list[str]:
    """A column's values as text (see `cell`), formatted a whole block at once;
    right-aligned in `width` characters if given."""
    if fmt == "s":
        return [str(v).rjust(width) for v in values_of(chunk)]
    x = np.asarray(values_of(chunk), dtype=float)
    spec = f">{width}{_SPECS[fmt]}" if width else _SPECS[fmt]
    out = list(map(("{:" + spec + "}").format, x.tolist()))
    for i in np.flatnonzero(~np.isfinite(x)).tolist():
        out[i] = cell(fmt, x[i]).rjust(width)
    return out


def cell(fmt: str, v) -> str:
    """One value as text: "e" 1.234560E+00, "t" an instant to 9 digits, "g" 6 digits,
    "s" text; NaN and +Inf/-Inf as such."""
    if fmt == "s":
        return str(v)
    x = float(v)
    if x != x:
        return "NaN"
    if math.isinf(x):
        return "+Inf" if x > 0 else "-Inf"
    return format(x, _SPECS[fmt])


# ---------------------------------------------------------------- builders


def report_names(run: Run, kind: str) -> list[str]:
    """The names of every `kind` statement (PRINT, OUTPUT, RANGE, PREPARE), once each."""
    seen: dict[str, None] = {}
    for r in run.reports:
        if r.kind == kind:
            seen.update(dict.fromkeys(r.names))
    return list(seen)


def printed_names(run: Run) -> list[str]:
    """PRINT variables (with no PRINT, the OUTPUT ones, else every variable), less
    TIME and the TERMINAL values, which the printout gives after the table."""
    names = report_names(run, "PRINT") or report_names(run, "OUTPUT")
    if not names:
        names = [n for n in run.values if "#" not in n]
    return [n for n in names if n != "TIME" and n not in run.terminal]


def column_of(run: Run, name: str, index: np.ndarray) -> Sequence:
    if name in run.values:
        return _Take(run.values[name], index)
    return _Repeat(run.constants.get(name, math.nan), len(index))


def printout_table(run: Run, names: list[str] | None = None, grid: str = "PRDEL") -> Table:
    """TIME and the PRINT variables on the PRDEL grid (or OUTDEL: `grid="OUTDEL"`)."""
    names = printed_names(run) if names is None else names
    index = np.flatnonzero(run.prdel_mask if grid == "PRDEL" else run.outdel_mask)
    cols = [Column("TIME", _Take(run.times, index))]
    cols += [Column(n, column_of(run, n, index)) for n in names]
    return Table("printout", cols)


LAB_RANGE_HEAD = ("RANGE", "MINIMUM", "TIME", "MAXIMUM", "TIME")


def range_table(run: Run, head: Sequence[str] = LAB_RANGE_HEAD) -> Table | None:
    names = report_names(run, "RANGE")
    if not names:
        return None
    rng = run.range
    rows = []
    for n in names:
        if n in rng:
            rows.append(rng[n])
        else:
            v = run.constants.get(n, math.nan)
            rows.append((v, 0.0, v, 0.0))
    cols = [Column(head[0], names, "s", left=True)]
    cols += [Column(h, [r[k] for r in rows]) for k, h in enumerate(head[1:])]
    return Table("range", cols)


LAB_DATA_HEAD = ("TIME", "VARIABLE", "OBSERVED", "SIMULATED", "RESIDUAL")
LAB_FIT_HEAD = ("VARIABLE", "N", "RMS RESIDUAL", "MAX |RESIDUAL|")


def observed_table(run: Run, head: Sequence[str] = LAB_DATA_HEAD) -> Table | None:
    """Every observation (`--data`) against the run, variable by variable in time
    order; residual = observed - simulated."""
    if not run.observed:
        return None
    cs = run.observed
    cols = [Column(head[0], np.concatenate([c.t for c in cs]), "t"),
            Column(head[1], [c.name for c in cs for _ in c.t], "s", left=True)]
    for h, key in zip(head[2:], ("observed", "simulated", "residual"), strict=True):
        cols.append(Column(h, np.concatenate([getattr(c, key) for c in cs])))
    return Table("observed", cols)


def residual_table(run: Run, head: Sequence[str] = LAB_FIT_HEAD) -> Table | None:
    """Per observed variable: how many observations, the RMS and the largest
    |residual| (with a note of any past a failed run's end)."""
    if not run.observed:
        return None
    cs = run.observed
    table = Table("residuals", [
        Column(head[0], [c.name for c in cs], "s", left=True),
        Column(head[1], [str(len(c.t)) for c in cs], "s"),
        Column(head[2], [c.rms for c in cs]), Column(head[3], [c.largest for c in cs])])
    table.notes += [f"{c.name}: {c.unreached} observation(s) past the run's end left out"
                    for c in cs if c.unreached]
    return table


def events_table(run: Run, words: dict[str, str], limit: int = 60) -> Table | None:
    """TIME, switch and change of each event; the first and last `limit`/2 when
    there are more, with a note of how many are left out."""
    events = run.events
    if not events:
        return None
    shown = events if len(events) <= limit else events[: limit // 2] + events[-limit // 2:]
    table = Table("events", [
        Column("TIME", [e.time for e in shown], "t"),
        Column(words["switch"], [e.switch for e in shown], "s", left=True),
        Column(words["change"], [e.change() for e in shown], "s", left=True)],
        caption=f"{words['events']} ({len(events)})")
    if len(events) > limit:
        table.notes.append(f"… {len(events) - limit} {words['more']} …")
    return table


def terminal_table(run: Run, words: dict[str, str]) -> Table | None:
    if not run.terminal:
        return None
    return Table("terminal", [
        Column(words["name"], list(run.terminal), "s", left=True),
        Column(words["value"], list(run.terminal.values()))], caption=words["terminal"])


def data_table(rows: list[tuple[str, float, str, str, str]], words: dict[str, str]) -> Table:
    """(name, value, unit, description, where defined) rows as a table; the unit
    and description columns only when some value has one."""
    cols = [Column(words["name"], [r[0] for r in rows], "s", left=True),
            Column(words["value"], [r[1] for r in rows], "g")]
    for k, key in ((2, "unit"), (3, "description")):
        if any(r[k] for r in rows):
            cols.append(Column(words[key], [r[k] for r in rows], "s", left=True))
    cols.append(Column(words["defined"], [r[4] for r in rows], "s", left=True))
    return Table("data", cols)


# ------------------------------------------------------------ fixed width


def widths(table: Table) -> list[int]:
    """Column widths for the fixed-width form: WIDTH for numbers (more for a longer
    header), and for text at least WIDTH, else the longest cell (or header) + 2."""
    out = []
    for c in table.columns:
        if c.fmt == "s":
            longest = max((len(str(v)) for v in c.values), default=0)
            out.append(max(WIDTH, longest + 4, len(c.name) + 4))
        else:
            out.append(max(WIDTH, len(c.name) + 2))
    return out


def _fit(text: str, width: int, left: bool, first: bool = False) -> str:
    if not left:
        return text.rjust(width)
    return text.ljust(width) if first else "  " + text.ljust(width - 2)


def text_blocks(table: Table, max_chars: int | None = None,
                per_block: int = COLUMNS_PER_BLOCK
                ) -> Iterator[tuple[str, Iterator[str]]]:
    """The table in fixed-width text, as (header line, row lines) per block of
    columns. The first column (TIME, a name) starts every block; the others are
    split into blocks of `per_block`, fewer when `max_chars` would be exceeded."""
    w = widths(table)
    first, rest = table.columns[0], list(range(1, len(table.columns)))
    blocks: list[list[int]] = []
    for k in rest:
        fits = max_chars is None or (
            blocks and sum(w[j] for j in [0, *blocks[-1], k]) <= max_chars)
        if blocks and len(blocks[-1]) < per_block and fits:
            blocks[-1].append(k)
        else:
            blocks.append([k])
    for block in blocks or [[]]:
        cols = [first] + [table.columns[j] for j in block]
        ws = [w[0]] + [w[j] for j in block]
        firsts = [True] + [False] * (len(cols) - 1)
        head = "".join(_fit(c.name, wj, c.left, f)
                       for c, wj, f in zip(cols, ws, firsts, strict=True))
        yield head.rstrip(), _lines(table, cols, ws, firsts)


def _lines(table: Table, cols: list[Column], ws: list[int], firsts: list[bool]
           ) -> Iterator[str]:
    n = len(table)
    for start in range(0, n, CHUNK):
        part = slice(start, min(start + CHUNK, n))
        padded = [cells(c.fmt, c.values[part], wj) if not c.left else
                  [_fit(v, wj, True, f) for v in cells(c.fmt, c.values[part])]
                  for c, wj, f in zip(cols, ws, firsts, strict=True)]
        yield from ("".join(r).rstrip() for r in zip(*padded, strict=True))
