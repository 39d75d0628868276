"""The writer table: every file a command can write, one row each.

The command line makes its options from this table (`flag`, `help`) and, after
the runs, calls each writer that was asked for, before the printout, so that a
closed or blocked stdout cannot lose a file. A writer that fails raises an
`OutputError`; the others are still written. A new format (Parquet, HDF5, ...)
is one row here and a function.

Standard library only at import: the command line builds its options from this
table before it knows whether it will need numpy.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass

from .options import Outputs


@dataclass(frozen=True)
class Writer:
    name: str
    command: str  # the command that offers it
    flag: str | None  # the option asking for it; None: the listing asks (PREPARE)
    takes_path: bool  # the option names the file; else the files go to --out
    help: str
    write: Callable[[Outputs, str | None], list[str]]  # (outputs, the option's path) -> paths
    wanted: Callable[[Outputs], bool] | None = None  # for flag None: whether it is asked for


def _prepare(o: Outputs, _path: str | None) -> list[str]:
    from . import sheets
    from .tables import report_names

    path = os.path.join(o.out_dir, f"{o.stem}.csv")
    sheets.write_csv(path, o.runs, report_names(o.runs[0], "PREPARE"), dialect=o.dialect)
    return [path]


def _csv(o: Outputs, path: str | None) -> list[str]:
    from . import sheets

    if o.streamed is not None:  # (streamed as the runs went: its notes and header)
        o.streamed.close(sheets.partial_notes(o.runs), [r.params for r in o.runs])
    else:
        sheets.write_csv(path, o.runs, o.names, dialect=o.dialect)
    return [path]


def _xlsx(o: Outputs, path: str | None) -> list[str]:
    from . import sheets

    sheets.write_xlsx(path, o.runs, o.names)
    return [path]


def _png(o: Outputs, _path: str | None) -> list[str]:
    from .plot import plot_runs
    from .words import name_notes

    notes = name_notes(o.model.ir) if o.model is not None else None
    return plot_runs(o.runs, o.out_dir, o.stem, o.plot, notes)


def _sweep_csv(o: Outputs, path: str | None) -> list[str]:
    from . import sheets
    from .sweeps import csv_rows

    header, rows = csv_rows(o.sweep)
    sheets.write_csv_rows(path, header, rows, o.dialect)
    return [path]


def _sweep_png(o: Outputs, _path: str | None) -> list[str]:
    from .sweeps import plot_sweep, sweep_figure_stem, units

    titles = o.model.ir.runs[0].titles if o.model is not None else []
    title = titles[0] if titles else None
    axis_units = units(o.model, o.sweep) if o.model is not None else ("", "")
    return plot_sweep(o.sweep, sweep_figure_stem(o.out_dir, o.stem), title, axis_units,
                      o.plot.formats)


def _fit_png(o: Outputs, _path: str | None) -> list[str]:
    from .plot import plot_runs
    from .words import name_notes

    return plot_runs(o.analysis.fitted, o.out_dir, o.stem + "_fit", o.plot,
                     name_notes(o.model.ir))


def _fit_listing(o: Outputs, path: str | None) -> list[str]:
    from ..analysis.fit import written_listing
    from .files import atomic_write

    atomic_write(path, written_listing(o.model, o.analysis.values).encode("utf-8"))
    return [path]


def _csv_of(module: str, rows: str, comments=None, needs: str | None = None):
    """A writer of one CSV table: `rows(o.analysis)` of amilpy.output.<module> gives
    (header, rows); `comments(o.analysis)` the lines above them; `needs`: the flag
    that needs the linear model (`_need_linear`)."""
    def write(o: Outputs, path: str | None) -> list[str]:
        from importlib import import_module

        from . import sheets

        if needs:
            _need_linear(o, needs)
        header, body = getattr(import_module(f"amilpy.output.{module}"), rows)(o.analysis)
        sheets.write_csv_rows(path, header, body, o.dialect,
                              comments(o.analysis) if comments else ())
        return [path]
    return write


def _figure_of(module: str, draw: str, what: str, needs: str | None = None):
    """A writer of an analysis's figures: `draw(o.analysis, stem, o.model, formats=...)`
    of amilpy.output.<module>, the files named NAME_<what>...; `needs` as `_csv_of`."""
    def write(o: Outputs, _path: str | None) -> list[str]:
        from importlib import import_module

        from .analysis import figure_stem

        if needs:
            _need_linear(o, needs)
        fn = getattr(import_module(f"amilpy.output.{module}"), draw)
        return fn(o.analysis, figure_stem(o.out_dir, o.stem, what), o.model,
                  formats=o.plot.formats)
    return write


def _partial_curve(resp) -> list[str]:
    return [] if resp.complete else ["partial: the curve ends short of the range"]


def _steady_npz(o: Outputs, path: str | None) -> list[str]:
    from .files import atomic_write
    from .steady import npz_bytes

    atomic_write(path, npz_bytes(o.analysis))
    return [path]


def _partial(mc) -> list[str]:
    if mc.done < mc.runs:
        return [f"partial: {mc.done} of the {mc.runs} runs were done"]
    return []


def _short(result) -> list[str]:
    if getattr(result, "interrupted", False) or getattr(result, "timed_out", False):
        return ["partial: the study stopped early; the indices are of the runs done"]
    return []


def _need_linear(o: Outputs, flag: str) -> None:
    from .files import OutputError

    lin = o.analysis.linear
    if lin is None or not lin.inputs or not lin.outputs:
        raise OutputError(f"{flag} needs the linear model: give --input NAME and "
                          "--output NAME")


WRITERS: tuple[Writer, ...] = (
    Writer("prepare", "run", None, False,
           "PREPARE in the listing: its variables as NAME.csv in --out", _prepare,
           wanted=lambda o: any(r.kind == "PREPARE" for r in o.runs[0].reports)
           if o.runs else False),
    Writer("csv", "run", "--csv", True,
           "write every PRINT and OUTPUT variable (or --vars) on the OUTDEL grid of "
           "every run as CSV (a RUN column and the changed values first when there are "
           "several runs)", _csv),
    Writer("xlsx", "run", "--xlsx", True,
           "write them as an Excel workbook, one sheet per run (needs XlsxWriter: "
           "pip install 'amilpy[xlsx]')", _xlsx),
    Writer("png", "run", "--plot", False,
           "draw one figure per OUTPUT statement, saved as PNG (or --format) next to the "
           "model or in --out (and shown when a display can)", _png),
    Writer("sweep-csv", "sweep", "--csv", True,
           "write the sweep's table (one row per value) as CSV", _sweep_csv),
    Writer("sweep-png", "sweep", "--plot", False,
           "draw the characteristic (half peak-to-peak against the value) as "
           "NAME_sweep.png next to the model or in --out", _sweep_png),
    Writer("modes-csv", "modes", "--csv", True,
           "write the modes as CSV: RE, IM, WN, FHZ, ZETA, the shape per state (real "
           "parts, then IM_<state>)", _csv_of("analysis", "modes_csv")),
    Writer("periodic-csv", "periodic", "--csv", True,
           "write the orbit as CSV: PERIOD, MIN_/MAX_/MEAN_/HALF_PP_ of each measured "
           "variable, STABLE, MU_MAX", _csv_of("analysis", "orbit_csv")),
    Writer("periodic-png", "periodic", "--plot", False,
           "draw the measured variables over one period as NAME_periodic.png next to "
           "the model or in --out", _figure_of("analysis", "plot_orbit", "periodic")),
    Writer("response-csv", "response", "--csv", True,
           "write the curve as CSV, one row per orbit along it (folds in place, "
           "KIND fold)", _csv_of("analysis", "response_csv", _partial_curve)),
    Writer("response-png", "response", "--plot", False,
           "draw half peak-to-peak against the value (stable solid, unstable dashed, "
           "folds marked) as NAME_response.png next to the model or in --out",
           _figure_of("analysis", "plot_response", "response")),
    Writer("fit-csv", "fit", "--csv", True,
           "write the estimates as CSV: NAME, START, ESTIMATE, SE, LOWER95, UPPER95",
           _csv_of("fitting", "fit_csv")),
    Writer("fit-png", "fit", "--plot", False,
           "draw the fitted runs with the observations as NAME_fit_K.png next to the "
           "model or in --out", _fit_png),
    Writer("fit-listing", "fit", "--write", True,
           "write the listing with the fitted values in place (comments kept)",
           _fit_listing),
    Writer("steady-csv", "steady", "--csv", True,
           "write the equilibrium as CSV: NAME, VALUE, RATE, ROLE (solved, held, free)",
           _csv_of("steady", "steady_csv")),
    Writer("steady-matrices", "steady", "--matrices", True,
           "write A, B, C, D of the linear model (--input, --output) as CSV in long form: "
           "MATRIX, ROW, COLUMN, VALUE", _csv_of("steady", "matrices_csv", needs="--matrices")),
    Writer("steady-npz", "steady", "--npz", True,
           "write the equilibrium, its eigenvalues and A, B, C, D with their names as a "
           "NumPy .npz (numpy.load)", _steady_npz),
    Writer("steady-bode", "steady", "--bode", False,
           "draw the Bode diagram of every output to every input as NAME_bode_INPUT.png "
           "next to the model or in --out", _figure_of("steady", "plot_bode", "bode", "--bode")),
    Writer("montecarlo-csv", "montecarlo", "--csv", True,
           "write the bands as CSV on the output grid: TIME, NAME_MEAN and NAME_P<q> of "
           "each variable, RUNS", _csv_of("montecarlo", "bands_csv", _partial)),
    Writer("montecarlo-samples", "montecarlo", "--samples", True,
           "write every run as CSV: RUN, STATUS, the drawn values, FINAL_<NAME>, the "
           "TERMINAL values, a failed run's MESSAGE",
           _csv_of("montecarlo", "samples_csv", _partial)),
    Writer("montecarlo-png", "montecarlo", "--plot", False,
           "draw the bands (median line, quantiles shaded) of each OUTPUT statement as "
           "NAME_montecarlo_K.png next to the model or in --out",
           _figure_of("montecarlo", "plot_bands", "montecarlo")),
    Writer("sensitivity-csv", "sensitivity", "--csv", True,
           "write the sensitivities as CSV: local, TIME and per variable its value, "
           "S_<VAR>_<P> and D_<VAR>_<P>; global, a row per output and value",
           _csv_of("sensitivity", "sensitivity_csv", _short)),
    Writer("sensitivity-png", "sensitivity", "--plot", False,
           "draw them: local, S against TIME per variable (NAME_sensitivity_VAR.png); "
           "global, bars of the indices (NAME_sensitivity.png)",
           _figure_of("sensitivity", "plot_sensitivity", "sensitivity")),
)


def writers_for(command: str) -> list[Writer]:
    return [w for w in WRITERS if w.command == command]


def dest(flag: str) -> str:
    """The argparse attribute of a flag: "--csv" -> "csv"."""
    return flag.lstrip("-").replace("-", "_")
