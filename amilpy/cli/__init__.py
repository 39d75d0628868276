"""The command line: `amilpy run`, `sweep`, `report`, `check`, and the analyses
`modes`, `periodic`, `response` (analysis.py); signals, stdout and the progress line
in console.py.

Exit codes (the highest that applies, over every file given):
  0  success
  1  a fault in a listing (diagnostics on stderr, file:line:col)
  2  a usage error (a bad option or value; the message names it)
  3  a run failed or was interrupted (Ctrl-C, SIGTERM, SIGHUP): what it computed
     is still printed and written, marked partial
  4  an output could not be written (the path and the reason on stderr); the
     other outputs are still written
Errors are rendered here, once; no traceback reaches the user. Output files are
written before the printout, so a closed or blocked stdout cannot lose them.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from .. import __version__, interrupts
from ..diagnostics import AmilError, UsageError
from ..language import fortran_float, given_name
from ..output.files import OutputError
from ..output.options import Outputs, PlotOptions
from ..output.writers import WRITERS, dest
from ..routes import methods_help, route_for
from .common import (
    COUNT,
    EXIT_FAILED,
    EXIT_MODEL,
    EXIT_OK,
    EXIT_OUTPUT,
    EXIT_USAGE,
    FINITE,
    NONNEGATIVE,
    POSITIVE,
    csv_dialect,
    figure_options,
    finish,
    format_option,
    method_name,
    parse_sets,
    run_numbers,
    stem_and_dir,
    variable_names,
    write_outputs,
    writer_options,
    written_and_printed,
)
from .console import (
    STDOUT_FAILED,
    Progress,
    Signals,
    TimeLimit,
    time_limit,
    tolerant_streams,
    write_out,
)

# the modules whose warnings the command line does not show (see `_main`)
LIBRARIES = r"(scipy|numpy|matplotlib|numba|lark)(\.|$)"



# ------------------------------------------------------------------ parser


def _data_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--data", metavar="FILE",
                   help="a CSV of observations (TIME and variables' columns, optional "
                        "SD_<NAME> and RUN): drawn over the lines, tabled against the "
                        "run with residuals (see docs/fitting.md)")


def _model_options(p: argparse.ArgumentParser, seed: str | None = None,
                   method: str = "--method") -> None:
    """The options of a run; `seed`: what --seed seeds, where not the random streams;
    `method`: the integration method's flag, where --method names something else."""
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[],
                   help="override a PARAM/CONST/INCON value for every run (repeatable)")
    p.add_argument(method, dest="method", metavar="NAME", type=method_name,
                   help="integration method, instead of METHOD: " + methods_help())
    p.add_argument("--compiled", dest="method", action="store_const", const="COMPILED",
                   help="the same as --method COMPILED (needs pip install 'amilpy[fast]'; "
                        "the first run of a listing compiles it, about 1 s)")
    p.add_argument("--rtol", type=POSITIVE, metavar="X", help="relative tolerance (RELERR)")
    p.add_argument("--atol", type=POSITIVE, metavar="X", help="absolute tolerance (ABSERR)")
    p.add_argument("--fintim", type=POSITIVE, metavar="S", help="run length instead of FINTIM")
    p.add_argument("--step-point", action="store_true", default=None,
                   help="run a fixed-step method in step-point mode, as the classic "
                        "translators did: switches read at the step points, nothing "
                        "located (METHOD EULER/RECT always is)")
    p.add_argument("--seed", type=FINITE, metavar="N",
                   help=seed or "seed of the random streams (GAUSS, UNIF, OU...), instead "
                                "of the listing's RNSEED (default 1)")
    p.add_argument("--weather-dir", metavar="DIR", action="append", default=[],
                   help="a folder of CABO weather files for an FST listing's WEATHER, "
                        "looked in after WTRDIR, the listing's folder and its weather/ "
                        "and ../weather/ (repeatable)")
    p.add_argument("--max-time", type=POSITIVE, metavar="S",
                   help="wall-clock limit per run, seconds (reading, checking and "
                   "compiling the listing are bounded by it too)")
    p.add_argument("--max-steps", type=COUNT, metavar="N",
                   help="step limit per run (default 5000000)")
    p.add_argument("--max-events", type=COUNT, metavar="N",
                   help="event limit per run (default 200000)")


def _farm_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--jobs", type=COUNT, metavar="N",
                   help="worker processes for independent runs (value lists, END groups, "
                        "sweep points; default: every core)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run the independent runs on this Dask scheduler "
                        "(tcp://host:8786; pip install 'amilpy[cluster]')")


def _jobs(args) -> int:
    from ..batch.farm import default_jobs

    return args.jobs or default_jobs()


def _plot_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("plots")
    g.add_argument("--from", dest="t_from", type=FINITE, metavar="T1",
                   help="plot from TIME = T1 on")
    g.add_argument("--to", dest="t_to", type=FINITE, metavar="T2", help="plot up to TIME = T2")
    g.add_argument("--zoom-events", action="store_true",
                   help="also a figure of each OUTPUT statement around the first switching "
                        "event after start-up (NAME_zoom.png)")
    g.add_argument("--subplots", action="store_true",
                   help="one axis per variable (done anyway when scales differ over 100x)")
    g.add_argument("--runs", type=run_numbers, metavar="1,3", help="plot only these runs")


def _ensemble_parser(sub, command: str, summary: str, seed: str, method: str = "--method"
                     ) -> argparse.ArgumentParser:
    """A command over many runs of one listing (montecarlo, sensitivity): the listing,
    its files, the run options (--seed seeding the draws; `method` the integration
    method's flag) and the workers; the command adds its own."""
    p = sub.add_parser(command, help=summary)
    p.add_argument("file", metavar="FILE", help="the listing (.amil)")
    p.add_argument("--out", metavar="DIR", help="where the PNGs go (default: next to the "
                                                "listing)")
    writer_options(p, command)
    csv_dialect(p)
    format_option(p)
    _model_options(p, seed=seed, method=method)
    p.add_argument("--quiet", action="store_true", help="no printout, only files and errors")
    _farm_options(p)
    return p


def _parser() -> argparse.ArgumentParser:
    from ..output.report import FORMATS
    from ..output.words import LANGUAGES

    p = argparse.ArgumentParser(prog="amilpy", description="Run AMIL/CSMP-style simulation "
                                "listings: printouts, plots, CSV, sweeps and lab reports.",
                                epilog="Exit codes: 0 ok, 1 a fault in a listing, 2 a usage "
                                "error, 3 a run failed or was interrupted (partial results "
                                "kept), 4 an output could not be written.")
    p.add_argument("--version", action="version", version=f"amilpy {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    run = sub.add_parser("run", help="run listings: printout, plots, CSV")
    run.add_argument("files", nargs="+", metavar="FILE", help="the listing(s) (.amil)")
    run.add_argument("--out", metavar="DIR", help="where PREPARE's CSV and the PNGs go "
                                                  "(default: next to each listing)")
    writer_options(run, "run")
    run.add_argument("--vars", type=variable_names, metavar="A,B",
                     help="the variables --csv and --xlsx write (default: every PRINT, "
                          "OUTPUT and PREPARE variable)")
    csv_dialect(run)
    format_option(run)
    run.add_argument("--overlay", action="store_true",
                     help="with several listings: draw them in the same figures (the "
                          "first listing's OUTPUT statements, each listing a colour) as "
                          "FIRST_vs_SECOND.png, instead of a figure set each")
    run.add_argument("--ascii", action="store_true",
                     help="line-printer plots in the printout (as PRTPLT does)")
    _model_options(run)
    _data_option(run)
    run.add_argument("--show-python", action="store_true",
                     help="print the generated Python of the first run")
    run.add_argument("--quiet", action="store_true", help="no printout, only files and errors")
    run.add_argument("--no-advice", action="store_true",
                     help="do not probe for stiffness after an expensive explicit run")
    run.add_argument("--check-accuracy", action="store_true",
                     help="run each run again with RELERR/100 (a fixed step: DELT/4) and "
                          "say which printed digits stand and which variation is numerical")
    _farm_options(run)
    _plot_options(run)

    sw = sub.add_parser("sweep", help="one run per value of a data value (amplitude-"
                                      "frequency characteristics)")
    sw.add_argument("file", metavar="FILE", help="the listing (.amil)")
    sw.add_argument("range", metavar="NAME=START:STOP:STEP", nargs="+",
                    help="the data value swept and its values, STOP included; a second "
                         "range makes a grid (every pair of values, one run each)")
    sw.add_argument("--both-ways", action="store_true", help="sweep up, then back down")
    sw.add_argument("--carry-state", action="store_true",
                    help="each run continues from the previous run's final state (the "
                         "first point, a transient, is then left out of the jump search)")
    sw.add_argument("--settle", type=NONNEGATIVE, default=0.0, metavar="S",
                    help="measure only after S seconds of each run")
    sw.add_argument("--measure", metavar="VAR", help="the variable measured (default: the "
                                                     "first OUTPUT/PRINT variable)")
    sw.add_argument("--out", metavar="DIR", help="where the PNG goes (default: next to the "
                                                 "listing)")
    writer_options(sw, "sweep")
    csv_dialect(sw)
    format_option(sw)
    _model_options(sw)
    sw.add_argument("--quiet", action="store_true", help="no table, only files and errors")
    _farm_options(sw)

    mc = _ensemble_parser(sub, "montecarlo", "runs with data values drawn from "
                          "distributions: quantile bands, final and TERMINAL values, "
                          "failed runs", "seed of the draws (a whole number, default 1): the "
                          "same seed, the same runs, whatever --jobs or --scheduler (the "
                          "listing's random streams keep its RNSEED)")
    mc.add_argument("--dist", metavar="NAME=DIST", action="append", required=True,
                    type=_dist_option,
                    help="a data value and its distribution (repeatable): "
                         "normal(m,s), lognormal(m,s) (of the log), uniform(a,b), "
                         "triangular(a,c,b), truncnormal(m,s,a,b), table(FILE) (a CSV's "
                         "rows, its column NAME)")
    mc.add_argument("--runs", type=COUNT, metavar="N",
                    help="how many runs (default, when a --dist is a table: its rows, the "
                         "fewest of the tables')")
    mc.add_argument("--quantiles", default="5,50,95", metavar="LIST",
                    help="the percents of the bands and tables (default 5,50,95)")
    mc.add_argument("--correlate", metavar="A,B=R", action="append", default=[],
                    help="correlation R of two drawn names' normal scores (a Gaussian "
                         "copula; repeatable)")
    mc.add_argument("--vars", type=variable_names, metavar="A,B",
                    help="the variables (default: every PRINT and OUTPUT variable)")
    mc.add_argument("--one-by-one", action="store_true",
                    help="run the members one by one even where none switches on its own "
                         "and they could be integrated at once (to compare the two)")

    se = _ensemble_parser(sub, "sensitivity", "which data value matters: local "
                          "coefficients over time, or global Morris/Sobol indices",
                          "seed of the global method's draws (a whole number, default 1)",
                          method="--integrator")
    se.add_argument("--local", metavar="NAME", nargs="*",
                    help="local sensitivities (P/Y) dY/dP over the run to these data "
                         "values (default: the PARAM values), from the sensitivity "
                         "equations")
    se.add_argument("--method", dest="global_method", choices=("morris", "sobol"),
                    help="global indices over --dist distributions instead")
    se.add_argument("--dist", metavar="NAME=DIST", action="append", default=[],
                    type=_dist_option, help="a data value's distribution (as montecarlo)")
    se.add_argument("--runs", type=COUNT, metavar="N",
                    help="Sobol: rows N (N(k+2) runs, N a power of two); Morris: "
                         "trajectories r (r(k+1) runs)")
    se.add_argument("--measure", metavar="SPEC", action="append", default=[],
                    help="a global output: VAR (final value), VAR@T, max(VAR), min(VAR) "
                         "or a TERMINAL name (repeatable; default the first PRINT/OUTPUT "
                         "variable's final value)")
    se.add_argument("--vars", type=variable_names, metavar="A,B",
                    help="the variables of a local sensitivity (default: every PRINT and "
                         "OUTPUT variable)")

    rep = sub.add_parser("report", help="a lab-report document: listing, data, equations, "
                                        "printouts, events, plots")
    rep.add_argument("file", metavar="FILE", help="the listing (.amil)")
    rep.add_argument("--out", metavar="DIR", help="where the report and its PNGs go "
                                                  "(default: next to the listing)")
    rep.add_argument("--format", default="md", metavar="LIST",
                     help="comma-separated, of: " + "; ".join(
                         f"{k}: {f.help}" for k, f in FORMATS.items()) + " (default md)")
    rep.add_argument("--lang", choices=LANGUAGES,
                     help="language of the headings (default: Polish when the TITLE/LABEL "
                          "text is, else the locale's, else English)")
    rep.add_argument("--no-accuracy-check", action="store_true",
                     help="leave out the accuracy check (each run again with RELERR/100, "
                          "or DELT/4, which the report has by default)")
    _model_options(rep)
    _data_option(rep)
    _plot_options(rep)

    chk = sub.add_parser("check", help="parse and check listings, do not run them")
    chk.add_argument("files", nargs="+", metavar="FILE", help="the listing(s) (.amil)")
    from .analysis import add_parsers

    add_parsers(sub)
    return p


# ---------------------------------------------------------------- commands


def _plot_choice(args, model) -> PlotOptions:
    if args.t_from is not None and args.t_to is not None and args.t_from >= args.t_to:
        raise UsageError(f"--from {args.t_from:g} must come before --to {args.t_to:g}")
    if args.runs and max(args.runs) > len(model.ir.runs):
        raise UsageError(f"--runs {max(args.runs)}: the listing has {len(model.ir.runs)} "
                         "run(s)")
    from ..output.plot import can_show

    show = getattr(args, "plot", False) and can_show()
    return PlotOptions(args.t_from, args.t_to, args.zoom_events, args.subplots, args.runs,
                       show, getattr(args, "figure_formats", None) or ("png",))


def _load(args, path: str):
    """The listing read, checked and its first run compiled (into the model's cache,
    where the run finds it), within --max-time; and the --set values."""
    from ..api import load

    with time_limit(getattr(args, "max_time", None)):
        model = load(path)
        params = parse_sets(args.set)  # (the API says which names it does not have)
        model.python_source(weather_dir=getattr(args, "weather_dir", None), **params)
    return model, params


def cmd_run(args, path: str, signals: Signals) -> int:
    model, params = _load(args, path)
    plot = _plot_choice(args, model)
    # (TIME is every CSV's first column anyway)
    names = model.known_names([n for n in args.vars if n != "TIME"], data=True) \
        if args.vars else None
    if args.show_python:
        write_out(lambda out: out.write(model.python_source(weather_dir=args.weather_dir,
                                                            **params) + "\n"))
    progress = Progress(not args.quiet)
    stream = _csv_stream(args, model, names, params)
    try:
        runs = model.run(method=args.method, rtol=args.rtol, atol=args.atol,
                         progress=progress, max_time=args.max_time, max_steps=args.max_steps,
                         max_events=args.max_events, fintim=args.fintim,
                         advice=not args.no_advice, step_point=args.step_point,
                         seed=args.seed, weather_dir=args.weather_dir, jobs=_jobs(args),
                         scheduler=args.scheduler, data=args.data, stream_csv=stream,
                         csv_names=names, csv_dialect=args.csv_dialect, **params)
    except BaseException:
        if stream is not None:
            stream.discard()
        raise
    finally:
        progress.done()
    stem, out_dir = stem_and_dir(path, args.out)
    outputs = Outputs("run", stem, out_dir, runs, model=model, dialect=args.csv_dialect,
                      plot=plot, names=names, streamed=stream)
    if args.overlay:  # (drawn with the other listings' once all have run)
        args.overlaid.append((stem, model, runs, plot))
    written, errors = write_outputs(outputs, args, signals,
                                     skip=("png",) if args.overlay else ())
    if not args.quiet and not signals.held_back:
        from ..output.printout import write_runs

        write_out(lambda out: write_runs(out, runs, ascii_plots=args.ascii))
    if args.check_accuracy and not signals.held_back:
        from ..output.words import WORDS, accuracy_lines

        checks = model.check_accuracy(runs, fintim=args.fintim, step_point=args.step_point,
                                      seed=args.seed, weather_dir=args.weather_dir,
                                      **params)
        write_out(lambda out: out.write("".join(
            f"\nACCURACY CHECK, {c.label or 'run ' + str(k + 1)}"
            + (f" ({c.how})" if c.how else "") + "\n"
            + "".join(f"  {line}\n" for line in accuracy_lines(c, WORDS["en"]))
            for k, c in enumerate(checks))))
    code = finish(path, written, errors, args.quiet, signals)
    for r in runs:
        if r.advice and not args.quiet:
            print(f"amilpy: note: {r.advice}", file=sys.stderr)
    failed = [r for r in runs if not r.ok]
    for r in failed:
        print(f"amilpy: {path}: run {r.label!r}: {r.message}", file=sys.stderr)
    return max(code, EXIT_FAILED if failed else EXIT_OK)


# --csv streams the rows to the file as the runs go (output/stream.py) when they
# would keep more values than this in memory (40 MB): one long run, say
STREAM_VALUES = 5_000_000


def _csv_stream(args, model, names, params):
    """The CsvStream for --csv when the runs are long, else None (a short run's CSV
    is written from its rows after it, with --xlsx, or where the path is no
    regular file in a folder that exists: the writer says what is wrong there)."""
    from ..output.files import is_stream

    path = args.csv
    # (what reads every row after the runs cannot take a streamed run: --xlsx, the
    # accuracy check's comparison, PREPARE's file)
    if not path or args.xlsx or args.check_accuracy or is_stream(path) or \
            model.ir.acsl is not None or \
            any(r.kind == "PREPARE" for spec in model.ir.runs for r in spec.reports) or \
            not os.path.isdir(os.path.dirname(os.path.abspath(path))) or \
            (os.path.lexists(path) and not os.path.isfile(path)):
        return None
    from ..run.plan import DEFAULTS

    # (many values, or more rows than a run may keep whatever their values)
    if model.stored_values(args.fintim, **params) <= STREAM_VALUES and \
            model.most_rows(args.fintim, **params) <= DEFAULTS["max_rows"]:
        return None
    from ..output.stream import CsvStream

    try:
        return CsvStream(path, names, args.csv_dialect,
                         [s.data for s in model._specs(params)])
    except OSError:
        return None


def cmd_sweep(args, path: str, signals: Signals) -> int:
    from ..batch.sweep import parse_range, sweep

    if len(args.range) > 2:
        raise UsageError("give one range, or two for a grid (NAME=START:STOP:STEP each)")
    ranges = []
    for text in args.range:
        try:
            ranges.append(parse_range(text))
        except AmilError as exc:
            raise UsageError(f"the sweep range {text}: {exc}") from None
    (name, values), grid = ranges[0], (ranges[1] if len(ranges) > 1 else None)
    model, params = _load(args, path)  # (the sweep checks its names and options)
    progress = Progress(not args.quiet)
    total = 2 * len(values) - 1 if args.both_ways else \
        len(values) * (len(grid[1]) if grid else 1)
    progress.prefix = f"{name} point 1/{total}  "
    try:
        result = sweep(model, name, values, both_ways=args.both_ways,
                       carry_state=args.carry_state, settle=args.settle, measure=args.measure,
                       method=args.method, rtol=args.rtol, atol=args.atol, fintim=args.fintim,
                       keep_runs=False, progress=progress,
                       step_point=args.step_point, seed=args.seed,
                       weather_dirs=tuple(args.weather_dir),
                       jobs=1 if args.carry_state else _jobs(args), scheduler=args.scheduler,
                       grid=grid, max_time=args.max_time, max_steps=args.max_steps,
                       max_events=args.max_events, **params)
    finally:
        progress.done()
    stem, out_dir = stem_and_dir(path, args.out)
    outputs = Outputs("sweep", stem, out_dir, sweep=result, model=model,
                      dialect=args.csv_dialect, plot=figure_options(args))
    written, errors = write_outputs(outputs, args, signals)
    if not args.quiet and not signals.held_back:
        from ..output.sweeps import format_sweep

        write_out(lambda out: out.write(format_sweep(result)))
    code = finish(path, written, errors, args.quiet, signals)
    failed = [p for p in result.points if p.status == "failed"]
    for message in result.errors:
        print(f"amilpy: {path}: {message}", file=sys.stderr)
    if failed and args.carry_state:
        print(f"amilpy: {path}: the run at {name} = {failed[0].value:g} failed; the "
              "sweep stopped there", file=sys.stderr)
    elif failed and not result.errors:
        print(f"amilpy: {path}: {len(failed)} point(s) failed, first at {name} = "
              f"{failed[0].value:g}", file=sys.stderr)
    return max(code, EXIT_FAILED if failed or result.errors else EXIT_OK)


def _dist_option(text: str) -> tuple[str, str]:
    name, sep, dist = text.partition("=")
    if not sep or given_name(name) is None:
        raise argparse.ArgumentTypeError(f"takes NAME=DIST, e.g. K=lognormal(0,0.2), got "
                                         f"{text!r}")
    return given_name(name), dist.strip()


def _correlations(items: list[str]) -> list[tuple[str, float]]:
    """--correlate A,B=R as ("A,B", R) pairs (the API reads the names and refuses a
    pair given twice)."""
    out = []
    for item in items:
        pair, sep, value = item.partition("=")
        try:
            r = fortran_float(value)
        except ValueError:
            r = None
        if not sep or pair.count(",") != 1 or r is None:
            raise UsageError(f"--correlate takes A,B=R, e.g. KA,KE=0.5, got {item!r}")
        out.append((pair, r))
    return out


def _stopped_early(path: str, result, args, after: str) -> bool:
    """Say that an ensemble stopped before its last run (Ctrl-C, --max-time)."""
    if not (getattr(result, "interrupted", False) or getattr(result, "timed_out", False)):
        return False
    why = "interrupted" if result.interrupted else f"stopped at --max-time {args.max_time:g} s"
    print(f"amilpy: {path}: {why}{after}", file=sys.stderr)
    return True


def cmd_montecarlo(args, path: str, signals: Signals) -> int:
    from ..output.montecarlo import montecarlo_text

    correlation = _correlations(args.correlate)
    model, params = _load(args, path)
    progress = Progress(not args.quiet)
    progress.prefix = "montecarlo  "
    try:
        result = model.montecarlo(args.dist, args.runs, args.seed, quantiles=args.quantiles,
                                  correlation=correlation, outputs=args.vars,
                                  method=args.method, rtol=args.rtol, atol=args.atol,
                                  fintim=args.fintim, jobs=_jobs(args),
                                  scheduler=args.scheduler, progress=progress,
                                  max_time=args.max_time, max_steps=args.max_steps,
                                  max_events=args.max_events,
                                  weather_dir=args.weather_dir or None,
                                  stacked=not args.one_by_one, step_point=args.step_point,
                                  **params)
    finally:
        progress.done()
    code = written_and_printed("montecarlo", path, model, result, args, signals, montecarlo_text)
    if result.failed:
        print(f"amilpy: {path}: {len(result.failed)} of {result.runs} runs failed (listed, "
              "left out of the quantiles)", file=sys.stderr)
    short = _stopped_early(path, result, args, f" after {result.done} of {result.runs} "
                                               "runs; what was done is printed and written")
    return max(code, EXIT_FAILED if result.failed or short else EXIT_OK)


def cmd_sensitivity(args, path: str, signals: Signals) -> int:
    from ..output.sensitivity import indices_text, local_text

    if args.global_method and args.local is not None:
        raise UsageError("give --local or --method morris|sobol, not both")
    if not args.global_method and (args.dist or args.measure):
        raise UsageError("--dist and --measure are for global indices: add --method "
                         "morris or --method sobol")
    model, params = _load(args, path)
    progress = Progress(not args.quiet)
    progress.prefix = "sensitivity  "
    try:
        common = dict(method_ode=args.method, rtol=args.rtol, atol=args.atol,
                      fintim=args.fintim, max_time=args.max_time, max_steps=args.max_steps,
                      max_events=args.max_events, step_point=args.step_point,
                      weather_dir=args.weather_dir or None)
        if args.global_method:
            result = model.sensitivity(
                method=args.global_method, dists=args.dist, measures=args.measure,
                runs=args.runs, seed=args.seed, jobs=_jobs(args), scheduler=args.scheduler,
                progress=progress, **common, **params)
        else:
            result = model.sensitivity(args.local or None, outputs=args.vars, **common,
                                       **params)
    finally:
        progress.done()
    code = written_and_printed("sensitivity", path, model, result, args, signals,
                 indices_text if args.global_method else local_text)
    failed = getattr(result, "failed", [])
    if failed:
        print(f"amilpy: {path}: {len(failed)} of {result.runs} runs failed (listed)",
              file=sys.stderr)
    short = _stopped_early(path, result, args, ": the indices are of the runs done")
    return max(code, EXIT_FAILED if failed or short else EXIT_OK)


def cmd_report(args, path: str, signals: Signals) -> int:
    from ..output.report import FORMATS, write_report

    formats = [f.strip().lower() for f in args.format.split(",") if f.strip()]
    bad = [f for f in formats if f not in FORMATS]
    if bad or not formats:
        raise UsageError(f"--format takes {', '.join(FORMATS)}; got {args.format!r}")
    model, params = _load(args, path)
    plot = _plot_choice(args, model)
    runs = model.run(method=args.method, rtol=args.rtol, atol=args.atol, fintim=args.fintim,
                     max_time=args.max_time, max_steps=args.max_steps,
                     max_events=args.max_events, step_point=args.step_point, seed=args.seed,
                     weather_dir=args.weather_dir, data=args.data, **params)
    checks = None if args.no_accuracy_check else model.check_accuracy(
        runs, fintim=args.fintim, step_point=args.step_point, seed=args.seed,
        weather_dir=args.weather_dir, **params)
    errors: list[OutputError] = []
    with signals.held():
        written = write_report(model, runs, path, args.out, formats, args.lang, plot, errors,
                               checks)
    write_out(lambda out: out.write("".join(f"{fmt}: {', '.join(paths)}\n"
                                            for fmt, paths in written.items())))
    code = finish(path, [], list(dict.fromkeys(str(e) for e in errors)), True, signals)
    failed = [r for r in runs if not r.ok]
    for r in failed:
        print(f"amilpy: {path}: run {r.label!r}: {r.message}; the report is marked partial",
              file=sys.stderr)
    return max(code, EXIT_FAILED if failed else EXIT_OK)


def cmd_check(args, path: str, signals: Signals) -> int:
    from ..api import load
    from ..diagnostics import render

    ir = load(path).ir
    write_out(lambda out: out.write(
        f"{path}: ok — {len([s for s in ir.states if not s.hidden])} states, "
        f"{len(ir.dynamic)} equations, {len(ir.switches)} switches, {len(ir.runs)} run(s)\n"))
    if ir.warnings:
        print(render(ir.warnings, path, ir.source), file=sys.stderr)
    return EXIT_OK


def write_overlay(args, signals: Signals) -> int:
    """The figures of `run --overlay`: every listing that ran, in the same axes."""
    from ..output.plot import plot_overlay
    from ..output.words import name_notes

    listings = args.overlaid
    notes: dict[str, tuple[str, str]] = {}
    for _, model, _, _ in reversed(listings):  # (the first listing's units win)
        notes.update(name_notes(model.ir))
    first = args.files[0]
    _, out_dir = stem_and_dir(first, args.out)
    written, errors = [], []
    with signals.held():
        try:
            written = plot_overlay([(stem, runs) for stem, _, runs, _ in listings], out_dir,
                                   listings[0][3], notes)
        except OutputError as exc:
            errors.append(str(exc))
    return finish(first, written, errors, args.quiet, signals)


COMMANDS = {"run": cmd_run, "sweep": cmd_sweep, "montecarlo": cmd_montecarlo,
            "sensitivity": cmd_sensitivity, "report": cmd_report, "check": cmd_check}


def _same_file(args) -> str:
    """Two outputs asked into one file would leave only the last, and an output into
    the listing would replace it: what to say, or ""."""
    listings = {os.path.realpath(p) for p in (getattr(args, "files", None) or
                                              [getattr(args, "file", None)]) if p}
    seen: dict[str, str] = {}
    for w in WRITERS:
        target = getattr(args, dest(w.flag), None) if w.flag and w.takes_path else None
        if w.command != args.command or not isinstance(target, str):
            continue
        key = os.path.realpath(target)
        if key in listings:
            return f"{w.flag} {target} is the listing itself: give another file"
        if key in seen and seen[key] != w.flag:
            return f"{seen[key]} and {w.flag} name the same file, {target}: give each its own"
        seen[key] = w.flag
    return ""


def _one(command, args, path: str, signals: Signals) -> int:
    try:
        code = command(args, path, signals)
        if interrupts.pending():
            # (swallowed where no loop looked again: after the last run, say; what
            # the command wrote is complete)
            interrupts.handled()
            print(f"amilpy: {path}: interrupted", file=sys.stderr)
            code = max(code, EXIT_FAILED)
        return code
    except UsageError as exc:  # (the command line's, or the API's)
        print(f"amilpy: {path}: {exc.text()}", file=sys.stderr)
        return EXIT_USAGE
    except OutputError as exc:
        print(f"amilpy: {exc}", file=sys.stderr)
        return EXIT_OUTPUT
    except AmilError as exc:
        if exc.path is None:
            exc.path = path  # an error from a stage that did not know the file
        print(exc.render(), file=sys.stderr)
        return EXIT_MODEL
    except KeyboardInterrupt:
        interrupts.handled()
        print(f"amilpy: {path}: interrupted", file=sys.stderr)
        return EXIT_FAILED
    except ImportError:
        # an interrupt inside a compiled module's initialization (SciPy's, imported
        # when a run first needs it) comes out as "ImportError: initialization failed"
        if signals.received is None:
            raise
        interrupts.handled()
        print(f"amilpy: {path}: interrupted", file=sys.stderr)
        return EXIT_FAILED
    except TimeLimit:
        print(f"amilpy: {path}: reading, checking and compiling the listing took longer "
              f"than --max-time {args.max_time:g} s", file=sys.stderr)
        return EXIT_FAILED
    except MemoryError:
        print(f"amilpy: {path}: out of memory", file=sys.stderr)
        return EXIT_FAILED
    except RecursionError:
        print(f"amilpy: {path}: the listing is nested too deeply", file=sys.stderr)
        return EXIT_MODEL


def main(argv: list[str] | None = None) -> int:
    try:
        return _main(argv)
    except KeyboardInterrupt:  # (before the command's own handlers: building the parser)
        print("amilpy: interrupted", file=sys.stderr)
        return EXIT_FAILED


def _main(argv: list[str] | None) -> int:
    tolerant_streams()
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse has printed the usage (or --help, --version)
        return int(exc.code) if isinstance(exc.code, int) else EXIT_USAGE
    method = getattr(args, "method", None) and route_for(args.method)
    if getattr(args, "step_point", None) and method and method.uses_tolerances:
        print(f"amilpy {args.command}: --step-point needs a fixed-step method; --method "
              f"{args.method} chooses its own steps", file=sys.stderr)
        return EXIT_USAGE
    paths = getattr(args, "files", None) or [args.file]
    several = [w.flag for w in WRITERS if w.takes_path and w.flag
               and getattr(args, dest(w.flag), None)]
    if len(paths) > 1 and several:
        print(f"amilpy {args.command}: {several[0]} names one file; with several listings "
              "run them one at a time", file=sys.stderr)
        return EXIT_USAGE
    same = _same_file(args)
    if same:
        print(f"amilpy {args.command}: {same}", file=sys.stderr)
        return EXIT_USAGE
    if getattr(args, "figure_formats", None) or getattr(args, "overlay", False):
        args.plot = True  # (asking for figure files or an overlay asks for figures)
    if getattr(args, "overlay", False):
        if len(paths) < 2:
            print(f"amilpy {args.command}: --overlay draws several listings in the same "
                  "figures; give two or more", file=sys.stderr)
            return EXIT_USAGE
        args.overlaid = []
    from .analysis import COMMANDS as ANALYSES

    command = {**COMMANDS, **ANALYSES}[args.command]
    signals = Signals()
    signals.install()
    # A library's warning (SciPy's "excess accuracy requested", NumPy's overflow in
    # matplotlib's ticks) is noise on a user's terminal, pointing into code they did
    # not write: amilpy says in its own words what came of it (the run's notes and
    # messages)
    try:
        code = EXIT_OK
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", module=LIBRARIES)
            for path in paths:
                code = max(code, _one(command, args, path, signals))
                if signals.received:
                    break  # an interrupt stops the files not yet started too
            if getattr(args, "overlay", False) and args.overlaid and not signals.received:
                code = max(code, write_overlay(args, signals))
        if STDOUT_FAILED:
            print(f"amilpy: cannot write the printout to standard output: "
                  f"{STDOUT_FAILED[0]}", file=sys.stderr)
            code = max(code, EXIT_OUTPUT)
        return code
    finally:
        STDOUT_FAILED.clear()
        signals.restore()
