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


def format_run(run: Run, index: int | None = None, total: int = 1,
               show_events: bool = True) -> str:
    out = io.StringIO()
    for title in run.titles:
        out.write(title + "\n")
    head = f"RUN {index}" if index is not None and total > 1 else "RUN"
    label = "" if run.label.startswith("RUN ") else f": {run.label}"
    out.write(f"{head}{label}   (METHOD {run.method}")
    if run.method not in ("RK4", "RKSFX", "SIMP", "EULER", "RECT", "TRAPZ", "ADAMS"):
        out.write(f", RELERR {run.rtol:g}, ABSERR {run.atol:g}")
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


def format_runs(runs: list[Run], show_events: bool = True) -> str:
    parts = [format_run(r, i + 1, len(runs), show_events) for i, r in enumerate(runs)]
    return ("\n" + "-" * 72 + "\n").join(parts)


# ------------------------------------------------------------------ files

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
