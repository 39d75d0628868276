"""Runs -> the lab printout: TITLE lines, the run's heading, a fixed-width E-format
table of TIME and the PRINT variables every PRDEL, line-printer plots, the RANGE
table, the switching events in the listing's terms, the TERMINAL values and notes.

The printout is written to a stream row by row (`write_runs`); `format_runs`
gives it as a string for tests and notebooks.
"""

from __future__ import annotations

import io
import math
from typing import TextIO

import numpy as np

from ..result import Run, Status
from . import tables as T

SYMBOLS = "*+ox#@%&"
PLOT_WIDTH = 51
PLOT_ROWS = 101
EVENTS_SHOWN = 40  # the first and last 20 of a longer list


def _e(x: float) -> str:
    return T.cell("e", x).rjust(T.WIDTH)


def printer_plot(run: Run, names: list[str], label: str | None = None) -> str:
    """The line-printer plot of CSMP's PRTPLT: time runs down the page, one row per
    output instant (at most 101, evenly thinned), the values printed beside a
    field where each variable has its symbol, on one scale from min to max."""
    t = run.t
    step = max(1, math.ceil(len(t) / PLOT_ROWS))
    rows = list(range(0, len(t), step))
    if rows and rows[-1] != len(t) - 1:
        rows.append(len(t) - 1)
    index = np.flatnonzero(run.outdel_mask)
    full = [np.asarray(T.column_of(run, n, index)[:], dtype=float) for n in names]
    cols = [c[rows] for c in full]
    finite = np.concatenate([c[np.isfinite(c)] for c in full]) if full else np.array([])
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    if hi == lo:
        lo, hi = lo - 1.0, hi + 1.0

    def column(v: float) -> int:
        # halves first: hi - lo overflows when the values span more than the largest
        # float (-1E308 .. 1E308), and inf/inf is no column
        frac = (0.5 * v - 0.5 * lo) / (0.5 * hi - 0.5 * lo)
        return int(round(min(max(frac, 0.0), 1.0) * (PLOT_WIDTH - 1)))

    zero = column(0.0) if lo < 0.0 < hi else None
    out = io.StringIO()
    if label:
        out.write(f"\n{label}\n")
    legend = "   ".join(f"{SYMBOLS[k % len(SYMBOLS)]} {n}" for k, n in enumerate(names))
    out.write(f"\nPRINTER PLOT   {legend}\n")
    pad = " " * (T.WIDTH * (1 + len(names)) + 1)
    scale = f"{lo:<.4E}".ljust(PLOT_WIDTH - 11) + f"{hi:>.4E}"
    out.write(pad + scale + "\n")
    out.write("TIME".rjust(T.WIDTH) + "".join(n.rjust(T.WIDTH) for n in names) + " "
              + "+" + "-" * (PLOT_WIDTH - 2) + "+\n")
    for k, i in enumerate(rows):
        field = [" "] * PLOT_WIDTH
        if zero is not None:
            field[zero] = "|"
        for j, c in enumerate(cols):
            if math.isfinite(c[k]):
                field[column(c[k])] = SYMBOLS[j % len(SYMBOLS)]
        out.write(_e(t[i]) + "".join(_e(c[k]) for c in cols) + " " + "".join(field) + "\n")
    return out.getvalue()


def printer_plots(run: Run, ascii_plots: bool = False) -> list[str]:
    """The line-printer plots a printout shows: one per PRTPLT (every OUTPUT with
    `ascii_plots`), or one of the PRINT variables when there is no OUTPUT."""
    plots = [printer_plot(run, [n for n in r.names if n != "TIME"], r.label)
             for r in run.reports if r.kind == "OUTPUT" and (r.printer or ascii_plots)]
    if ascii_plots and not any(r.kind == "OUTPUT" for r in run.reports):
        plots.append(printer_plot(run, T.printed_names(run)))
    return plots


def method_text(run: Run) -> str:
    """"METHOD AUTO, RELERR 1e-06, ABSERR 1e-09" or "METHOD RK4, DELT 0.015625"."""
    return f"METHOD {run.method}" + (f", {run.settings}" if run.settings else "")


def heading(run: Run, index: int | None = None, total: int = 1) -> str:
    head = f"RUN {index}" if index is not None and total > 1 else "RUN"
    label = "" if run.label.startswith("RUN ") else f": {run.label}"
    return f"{head}{label}   ({method_text(run)})"


def write_table(out: TextIO, table: T.Table, gap: str = "\n") -> None:
    """The table's blocks, each after `gap`, then its notes."""
    for head, rows in T.text_blocks(table):
        out.write(gap + head + "\n")
        for line in rows:
            out.write(line + "\n")
    out.write("".join(f"   {n}\n" for n in table.notes))


def write_run(out: TextIO, run: Run, index: int | None = None, total: int = 1,
              show_events: bool = True, ascii_plots: bool = False) -> None:
    for title in run.titles:
        out.write(title + "\n")
    out.write(heading(run, index, total) + "\n")
    write_table(out, T.printout_table(run))
    for plot in printer_plots(run, ascii_plots):
        out.write(plot)
    ranged = T.range_table(run)
    if ranged is not None:
        write_table(out, ranged)
    if run.observed:
        out.write(f"\nDATA ({run.observed[0].source})\n")
        write_table(out, T.observed_table(run), gap="")
        out.write("\nDATA SUMMARY\n")
        write_table(out, T.residual_table(run), gap="")
    if show_events and run.events:
        out.write(f"\nSWITCHING EVENTS ({len(run.events)})\n")
        events = run.events
        half = EVENTS_SHOWN // 2
        shown = events if len(events) <= EVENTS_SHOWN else events[:half] + events[-half:]
        for k, e in enumerate(shown):
            if len(events) > EVENTS_SHOWN and k == half:
                out.write(f"   ... {len(events) - EVENTS_SHOWN} more ...\n")
            out.write(f"   {e}\n")
    if run.terminal:
        out.write("\nTERMINAL\n")
        for name, value in run.terminal.items():
            out.write(f"   {name} = {T.cell('e', value)}\n")
    for w in run.warnings:
        out.write(f"\nNOTE: {w}\n")
    if run.status == Status.FAILED:
        out.write(f"\n*** PARTIAL RESULTS: {run.message}\n")
    elif run.status == Status.STOPPED:
        out.write(f"\n{run.message}\n")


SEPARATOR = "\n" + "-" * 72 + "\n"


def write_runs(out: TextIO, runs: list[Run], show_events: bool = True,
               ascii_plots: bool = False) -> None:
    for i, r in enumerate(runs):
        if i:
            out.write(SEPARATOR)
        write_run(out, r, i + 1, len(runs), show_events, ascii_plots)


def format_run(run: Run, index: int | None = None, total: int = 1,
               show_events: bool = True, ascii_plots: bool = False) -> str:
    out = io.StringIO()
    write_run(out, run, index, total, show_events, ascii_plots)
    return out.getvalue()


def format_runs(runs: list[Run], show_events: bool = True, ascii_plots: bool = False) -> str:
    out = io.StringIO()
    write_runs(out, runs, show_events, ascii_plots)
    return out.getvalue()
