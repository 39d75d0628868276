"""Runs -> the lab-report printout: TITLE lines, run label, a fixed-width
E-format table of TIME and the PRINT variables every PRDEL, the RANGE table,
the switching events; and CSV files (PREPARE, --csv), written atomically.
"""

from __future__ import annotations

import csv
import io
import math
import os
import tempfile

import numpy as np

from .result import Run, Status
from .routes import route_for

COLUMNS_PER_BLOCK = 7
WIDTH = 14


def _e(x: float) -> str:
    if x != x:
        return "NaN".rjust(WIDTH)
    if math.isinf(x):
        return ("+Inf" if x > 0 else "-Inf").rjust(WIDTH)
    return f"{x: .6E}".rjust(WIDTH)


def report_names(run: Run, kind: str) -> list[str]:
    names: list[str] = []
    for r in run.reports:
        if r.kind == kind:
            names.extend(n for n in r.names if n not in names)
    return names


def printed_names(run: Run) -> list[str]:
    """PRINT variables; with no PRINT statement, the OUTPUT ones, else every variable."""
    names = report_names(run, "PRINT") or report_names(run, "OUTPUT")
    if not names:
        names = [n for n in run.values if "#" not in n]
    return [n for n in names if n != "TIME"]


SYMBOLS = "*+ox#@%&"
PLOT_WIDTH = 51
PLOT_ROWS = 101


def printer_plot(run: Run, names: list[str], label: str | None = None) -> str:
    """The line-printer plot of CSMP's PRTPLT: time runs down the page, one row per
    output instant (at most 101, evenly thinned), the values printed beside a
    field where each variable has its symbol, on one scale from min to max."""
    t = run.t
    cols = []
    for n in names:
        try:
            cols.append(np.asarray(run[n], dtype=float))
        except KeyError:
            cols.append(np.full(t.shape, math.nan))
    finite = np.concatenate([c[np.isfinite(c)] for c in cols]) if cols else np.array([])
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    if hi == lo:
        lo, hi = lo - 1.0, hi + 1.0
    step = max(1, math.ceil(len(t) / PLOT_ROWS))
    rows = list(range(0, len(t), step))
    if rows[-1] != len(t) - 1:
        rows.append(len(t) - 1)

    def column(v: float) -> int:
        return int(round((v - lo) / (hi - lo) * (PLOT_WIDTH - 1)))

    zero = column(0.0) if lo < 0.0 < hi else None
    out = io.StringIO()
    if label:
        out.write(f"\n{label}\n")
    legend = "   ".join(f"{SYMBOLS[k % len(SYMBOLS)]} {n}" for k, n in enumerate(names))
    out.write(f"\nPRINTER PLOT   {legend}\n")
    pad = " " * (WIDTH * (1 + len(names)) + 1)
    scale = f"{lo:<.4E}".ljust(PLOT_WIDTH - 11) + f"{hi:>.4E}"
    out.write(pad + scale + "\n")
    out.write("TIME".rjust(WIDTH) + "".join(n.rjust(WIDTH) for n in names) + " "
              + "+" + "-" * (PLOT_WIDTH - 2) + "+\n")
    for i in rows:
        field = [" "] * PLOT_WIDTH
        if zero is not None:
            field[zero] = "|"
        for k, c in enumerate(cols):
            if math.isfinite(c[i]):
                field[column(c[i])] = SYMBOLS[k % len(SYMBOLS)]
        out.write(_e(t[i]) + "".join(_e(c[i]) for c in cols) + " " + "".join(field) + "\n")
    return out.getvalue()


def format_run(run: Run, index: int | None = None, total: int = 1,
               show_events: bool = True, ascii_plots: bool = False) -> str:
    out = io.StringIO()
    for title in run.titles:
        out.write(title + "\n")
    head = f"RUN {index}" if index is not None and total > 1 else "RUN"
    label = "" if run.label.startswith("RUN ") else f": {run.label}"
    out.write(f"{head}{label}   (METHOD {run.method}")
    if route_for(run.method).uses_tolerances:
        out.write(f", {run.settings}")
    out.write(")\n")
    names = printed_names(run)
    table = run.printout
    for start in range(0, max(len(names), 1), COLUMNS_PER_BLOCK):
        block = names[start:start + COLUMNS_PER_BLOCK]
        out.write("\n" + "TIME".rjust(WIDTH) + "".join(n.rjust(WIDTH) for n in block) + "\n")
        cols = [run.printout.columns[n] if n in table.columns else
                np.full(table.t.shape, run.constants.get(n, math.nan)) for n in block]
        for i, t in enumerate(table.t):
            out.write(_e(t) + "".join(_e(c[i]) for c in cols) + "\n")
    for r in run.reports:
        if r.kind == "OUTPUT" and (r.printer or ascii_plots):
            out.write(printer_plot(run, [n for n in r.names if n != "TIME"], r.label))
    if ascii_plots and not any(r.kind == "OUTPUT" for r in run.reports):
        out.write(printer_plot(run, names))
    ranged = report_names(run, "RANGE")
    if ranged:
        rng = run.range
        out.write("\n" + "RANGE".ljust(WIDTH) + "MINIMUM".rjust(WIDTH) + "TIME".rjust(WIDTH)
                  + "MAXIMUM".rjust(WIDTH) + "TIME".rjust(WIDTH) + "\n")
        for n in ranged:
            if n in rng:
                lo, tlo, hi, thi = rng[n]
            else:
                v = run.constants.get(n, math.nan)
                lo, tlo, hi, thi = v, 0.0, v, 0.0
            out.write(n.ljust(WIDTH) + _e(lo) + _e(tlo) + _e(hi) + _e(thi) + "\n")
    if show_events and run.events:
        out.write(f"\nSWITCHING EVENTS ({len(run.events)})\n")
        shown = run.events if len(run.events) <= 40 else run.events[:20] + run.events[-20:]
        for k, e in enumerate(shown):
            if len(run.events) > 40 and k == 20:
                out.write(f"   ... {len(run.events) - 40} more ...\n")
            out.write(f"   {e}\n")
    for w in run.warnings:
        out.write(f"\nNOTE: {w}\n")
    if run.status == Status.FAILED:
        out.write(f"\n*** PARTIAL RESULTS: {run.message}\n")
    elif run.status == Status.STOPPED:
        out.write(f"\n{run.message}\n")
    return out.getvalue()


def format_runs(runs: list[Run], show_events: bool = True, ascii_plots: bool = False) -> str:
    parts = [format_run(r, i + 1, len(runs), show_events, ascii_plots)
             for i, r in enumerate(runs)]
    return ("\n" + "-" * 72 + "\n").join(parts)


# ------------------------------------------------------------------ files

def _file_mode(path: str) -> int:
    try:
        return os.stat(path).st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def atomic_write(path: str, data: bytes) -> None:
    """Write a file so that it is either the old one or the complete new one."""
    directory = os.path.dirname(os.path.abspath(path)) or "."
    os.makedirs(directory, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".amilpy-", dir=directory)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        # mkstemp makes the file private (0600); the result is an ordinary file,
        # with the mode a plain open() would give it, or the one it had before
        os.chmod(tmp, _file_mode(path))
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def csv_text(runs: list[Run], names: list[str] | None = None) -> str:
    """CSV on the OUTDEL grid: a header row, a RUN column when there are several runs."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    if names is None:
        names = report_names(runs[0], "PREPARE") or printed_names(runs[0])
    several = len(runs) > 1
    for k, run in enumerate(runs, start=1):
        if not run.ok:
            # a failed run's rows are all here, but the file must say it is partial
            buf.write(f"# PARTIAL (run {k}): {run.message}\n")
    writer.writerow((["RUN"] if several else []) + ["TIME"] + names)
    for k, run in enumerate(runs, start=1):
        t = run.t
        cols = []
        for n in names:
            try:
                cols.append(run[n])
            except KeyError:
                cols.append(np.full(t.shape, math.nan))
        for i in range(len(t)):
            row = ([k] if several else []) + [repr(float(t[i]))] + \
                  [repr(float(c[i])) for c in cols]
            writer.writerow(row)
    return buf.getvalue()


def write_csv(path: str, runs: list[Run], names: list[str] | None = None) -> None:
    atomic_write(path, csv_text(runs, names).encode("utf-8"))
