"""Numbers for a spreadsheet: CSV in two dialects, and .xlsx when XlsxWriter is
installed (`pip install amilpy[xlsx]`).

Rows are streamed from the run's arrays a block at a time, so a file of a
million rows never exists as one string.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Iterator, Sequence
from typing import TextIO

import numpy as np

from ..result import Run
from . import tables as T
from . import words as W
from .files import OutputError, atomic_open
from .options import DIALECTS


def _number(decimal: str):
    if decimal == ".":
        return repr
    return lambda x: repr(x).replace(".", decimal)


def write_csv_stream(fh: TextIO, header: Sequence[str], rows: Iterable[Sequence],
                     dialect: str = "plain", comments: Sequence[str] = ()) -> None:
    """CSV to a text stream: `# ` comment lines, a header, then rows whose floats
    are written exactly (repr) with the dialect's decimal mark."""
    d = DIALECTS[dialect]
    num = _number(d.decimal)
    for line in comments:
        fh.write(f"# {line}{d.newline}")
    writer = csv.writer(fh, delimiter=d.delimiter, lineterminator=d.newline)
    writer.writerow(header)
    for row in rows:
        writer.writerow([num(v) if isinstance(v, float) else v for v in row])


def write_csv_rows(path: str, header: Sequence[str], rows: Iterable[Sequence],
                   dialect: str = "plain", comments: Sequence[str] = ()) -> None:
    with atomic_open(path, text=True, encoding=DIALECTS[dialect].encoding, newline="") as fh:
        write_csv_stream(fh, header, rows, dialect, comments)


def outdel_rows(run: Run, names: Sequence[str]) -> Iterator[tuple[float, ...]]:
    """(TIME, values of `names`) on the OUTDEL grid, read a block of rows at a time."""
    index = np.flatnonzero(run.outdel_mask)
    cols = [T.column_of(run, n, index) for n in names]
    for start in range(0, len(index), T.CHUNK):
        part = slice(start, start + T.CHUNK)
        block = [run.times[index[part]].tolist()]
        block += [[float(v) for v in T.values_of(c[part])] for c in cols]
        yield from zip(*block, strict=True)


def export_names(run: Run) -> list[str]:
    """The columns --csv and --xlsx write unless told (`--vars`): every PRINT,
    OUTPUT and PREPARE variable, an OUTPUT's X included, once each in the listing's
    order;
    with neither, the printout's. Not TIME (the first column anyway), nor a
    TERMINAL value, which is no column of the grid."""
    return export_names_from(run.reports, lambda n: n in run.values or n not in run.terminal) \
        or T.printed_names(run)


def export_names_from(reports, column) -> list[str]:
    """`export_names` from a run's reports before it has run: `column(name)` says
    whether a name is a column of the grid (not a TERMINAL value)."""
    seen: dict[str, None] = {}
    for r in reports:
        if r.kind in ("PRINT", "OUTPUT", "PREPARE"):
            seen.update(dict.fromkeys(r.names))
            if getattr(r, "x", None):
                seen[r.x] = None
    return [n for n in seen if n != "TIME" and column(n)]


def run_rows(runs: Sequence[Run], names: Sequence[str]) -> tuple[list[str], Iterator[list]]:
    """Header and rows of runs on their OUTDEL grids. With several runs, a RUN
    column and one column per data value that differs between them come first, so
    each row says which run it belongs to by number and by value."""
    changed = W.changed_names(runs) if len(runs) > 1 else []
    lead = [W.run_column([*changed, *names]), *changed] if len(runs) > 1 else []
    # (a data value both changed between the runs and asked for is its lead column)
    names = [n for n in names if n not in changed]

    def rows() -> Iterator[list]:
        for k, run in enumerate(runs, start=1):
            prefix = [k, *(float(run.params.get(n, math.nan)) for n in changed)] if lead \
                else []
            for r in outdel_rows(run, names):
                yield prefix + list(r)

    return lead + ["TIME", *names], rows()


def partial_notes(runs: Sequence[Run]) -> list[str]:
    # a failed run's rows are all there, but the file must say it is partial
    return [f"PARTIAL (run {k}): {run.message}" for k, run in enumerate(runs, start=1)
            if not run.ok]


def write_csv(path: str, runs: Sequence[Run], names: Sequence[str] | None = None,
              dialect: str = "plain") -> None:
    header, rows = run_rows(runs, list(names) if names is not None else export_names(runs[0]))
    write_csv_rows(path, header, rows, dialect, partial_notes(runs))


def csv_text(runs: Sequence[Run], names: Sequence[str] | None = None,
             dialect: str = "plain") -> str:
    """The CSV of `write_csv` as a string (small runs: tests, notebooks)."""
    header, rows = run_rows(runs, list(names) if names is not None else export_names(runs[0]))
    buf = io.StringIO()
    write_csv_stream(buf, header, rows, dialect, partial_notes(runs))
    return buf.getvalue()


# -------------------------------------------------------------------- xlsx

XLSX_ROWS = 1_048_576  # what one sheet holds


def write_xlsx(path: str, runs: Sequence[Run], names: Sequence[str] | None = None) -> None:
    """One sheet per run (named by its changed values), TIME and the CSV's columns
    as numbers; a failed run's sheet starts with the PARTIAL note."""
    try:
        import xlsxwriter
    except ImportError:
        raise OutputError(path, "writing .xlsx needs XlsxWriter: pip install "
                                "'amilpy[xlsx]' (or pip install XlsxWriter)") from None
    names = list(names) if names is not None else export_names(runs[0])
    labels = W.run_labels(runs)
    with atomic_open(path) as fh:
        book = xlsxwriter.Workbook(fh, {"constant_memory": True, "nan_inf_to_errors": True})
        used: set[str] = set()
        for k, (run, label) in enumerate(zip(runs, labels, strict=True), start=1):
            sheet = book.add_worksheet(_sheet_name(k, label, used))
            row = 0
            if not run.ok:
                sheet.write_string(row, 0, f"PARTIAL: {run.message}")
                row += 1
            index = np.flatnonzero(run.outdel_mask)
            if row + 1 + len(index) > XLSX_ROWS:
                book.close()
                raise OutputError(path, f"run {k} has {len(index)} rows; a sheet holds "
                                        f"{XLSX_ROWS - 1}: write CSV instead")
            sheet.write_row(row, 0, ["TIME", *names])
            for values in outdel_rows(run, names):
                row += 1
                sheet.write_row(row, 0, values)
        book.close()


def _sheet_name(k: int, label: str, used: set[str]) -> str:
    name = label or f"RUN {k}"
    for ch in "[]:*?/\\":
        name = name.replace(ch, " ")
    name = name[:31].strip() or f"RUN {k}"
    if name in used:
        name = f"RUN {k}"
    used.add(name)
    return name
