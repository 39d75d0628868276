"""The command line: `amilpy run`, `amilpy check`.

Exit codes: 0 success, 1 a fault in the model (diagnostics on stderr),
2 a usage error, 3 the integration failed (what was computed is still printed
and written, marked partial). Errors are rendered here, once; no traceback
reaches the user.
"""

from __future__ import annotations

import argparse
import os
import sys

from .diagnostics import AmilError
from .routes import methods_help

EXIT_OK, EXIT_MODEL, EXIT_USAGE, EXIT_FAILED = 0, 1, 2, 3


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="amilpy",
        description="Run AMIL/CSMP-style simulation listings.",
    )
    sub = p.add_subparsers(dest="command", required=True)

    run = sub.add_parser("run", help="run a listing: printout, plots, CSV")
    run.add_argument("file")
    run.add_argument("--plot", action="store_true", help="draw one figure per OUTPUT statement")
    run.add_argument("--ascii", action="store_true",
                     help="line-printer plots in the printout (as PRTPLT does)")
    run.add_argument("--out", metavar="DIR", help="where PNG/CSV files go (default: next to "
                                                  "the model)")
    run.add_argument("--csv", metavar="PATH", help="write the OUTDEL-grid values as CSV")
    run.add_argument("--set", metavar="NAME=VALUE", action="append", default=[],
                     help="override a PARAM/CONST/INCON value (repeatable)")
    run.add_argument("--method", metavar="NAME", help="integration method (as METHOD): "
                     + methods_help())
    run.add_argument("--rtol", type=float, help="relative tolerance (RELERR)")
    run.add_argument("--atol", type=float, help="absolute tolerance (ABSERR)")
    run.add_argument("--show-python", action="store_true",
                     help="print the generated Python of the first run")
    run.add_argument("--quiet", action="store_true", help="no printout, only files and errors")
    run.add_argument("--no-advice", action="store_true",
                     help="do not probe for stiffness after an expensive explicit run")
    run.add_argument("--max-time", type=float, metavar="S", help="wall-clock limit per run")
    run.add_argument("--max-steps", type=int, help="step limit per run (default 5e6)")
    run.add_argument("--max-events", type=int, help="event limit per run (default 2e5)")
    run.add_argument("--fintim", type=float, metavar="S", help="run length instead of FINTIM")

    sw = sub.add_parser("sweep", help="one run per value of a data value (amplitude-"
                                      "frequency characteristics)")
    sw.add_argument("file")
    sw.add_argument("range", metavar="NAME=START:STOP:STEP")
    sw.add_argument("--both-ways", action="store_true", help="sweep up, then back down")
    sw.add_argument("--carry-state", action="store_true",
                    help="each run continues from the previous run's final state")
    sw.add_argument("--settle", type=float, default=0.0, metavar="S",
                    help="measure only after S seconds of each run")
    sw.add_argument("--measure", metavar="VAR", help="the variable measured (default: the "
                                                     "first OUTPUT/PRINT variable)")
    sw.add_argument("--fintim", type=float, metavar="S", help="length of each run")
    sw.add_argument("--csv", metavar="PATH")
    sw.add_argument("--plot", action="store_true")
    sw.add_argument("--out", metavar="DIR")
    sw.add_argument("--set", metavar="NAME=VALUE", action="append", default=[])
    sw.add_argument("--method")
    sw.add_argument("--rtol", type=float)
    sw.add_argument("--atol", type=float)
    sw.add_argument("--quiet", action="store_true")

    rep = sub.add_parser("report", help="a lab-report document: listing, data, equations, "
                                        "printouts, events, plots")
    rep.add_argument("file")
    rep.add_argument("--out", metavar="DIR")
    rep.add_argument("--format", default="md", help="comma-separated: md, pdf, tex "
                                                    "(default md)")
    rep.add_argument("--set", metavar="NAME=VALUE", action="append", default=[])
    rep.add_argument("--method")

    chk = sub.add_parser("check", help="parse and check a listing, do not run it")
    chk.add_argument("file")
    return p


def _parse_sets(items: list[str]) -> dict[str, float]:
    out = {}
    for item in items:
        if "=" not in item:
            raise _Usage(f"--set takes NAME=VALUE, got {item!r}")
        name, value = item.split("=", 1)
        try:
            out[name.strip().upper()] = float(value.replace("D", "E").replace("d", "e"))
        except ValueError:
            raise _Usage(f"--set {name}: {value!r} is not a number") from None
    return out


class _Usage(Exception):
    pass


def cmd_check(args) -> int:
    from .api import load

    model = load(args.file)
    ir = model.ir
    print(f"{args.file}: ok — {len([s for s in ir.states if not s.hidden])} states, "
          f"{len(ir.dynamic)} equations, {len(ir.switches)} switches, {len(ir.runs)} run(s)")
    return EXIT_OK


class Progress:
    """A progress line on stderr for runs longer than about a second (TTY only)."""

    def __init__(self, enabled: bool) -> None:
        import time

        self.enabled = enabled and sys.stderr.isatty()
        self.clock = time.perf_counter
        self.start = self.clock()
        self.last = 0.0
        self.shown = False

    def __call__(self, t: float, fintim: float, events: int, steps: int) -> None:
        if not self.enabled:
            return
        now = self.clock()
        if now - self.start < 1.0 or now - self.last < 0.2:
            return
        self.last = now
        rate = steps / max(now - self.start, 1e-9)
        print(f"\rTIME {t:.6g} / {fintim:g}  ({100 * t / fintim:5.1f}%)  events {events}  "
              f"{rate:,.0f} steps/s ", end="", file=sys.stderr, flush=True)
        self.shown = True

    def done(self) -> None:
        if self.shown:
            print("\r" + " " * 72 + "\r", end="", file=sys.stderr, flush=True)


def cmd_run(args) -> int:
    from .api import load
    from .printout import format_runs, report_names, write_csv

    model = load(args.file)
    params = _parse_sets(args.set)
    if args.show_python:
        print(model.python_source(**params))
    progress = Progress(not args.quiet)
    runs = model.run(method=args.method, rtol=args.rtol, atol=args.atol, progress=progress,
                     max_time=args.max_time, max_steps=args.max_steps,
                     max_events=args.max_events, fintim=args.fintim,
                     advice=not args.no_advice, **params)
    progress.done()
    if not args.quiet:
        sys.stdout.write(format_runs(runs, ascii_plots=args.ascii))
        sys.stdout.flush()
    stem = os.path.splitext(os.path.basename(args.file))[0]
    out_dir = args.out or os.path.dirname(os.path.abspath(args.file))
    written = []
    if report_names(runs[0], "PREPARE"):
        path = os.path.join(out_dir, f"{stem}.csv")
        write_csv(path, runs)
        written.append(path)
    if args.csv:
        write_csv(args.csv, runs)
        written.append(args.csv)
    if args.plot:
        from .plot import display_available, plot_runs

        written.extend(plot_runs(runs, out_dir, stem, show=display_available()))
    if written and not args.quiet:
        print("\nwritten: " + ", ".join(written))
    for r in runs:
        if r.advice and not args.quiet:
            print(f"amilpy: note: {r.advice}", file=sys.stderr)
    failed = [r for r in runs if not r.ok]
    for r in failed:
        print(f"amilpy: {args.file}: run {r.label!r}: {r.message}", file=sys.stderr)
    return EXIT_FAILED if failed else EXIT_OK


def cmd_sweep(args) -> int:
    from .api import load
    from .printout import atomic_write
    from .sweep import parse_range, plot_sweep

    model = load(args.file)
    name, values = parse_range(args.range)
    params = _parse_sets(args.set)

    def progress(i, n, value):
        if not args.quiet and sys.stderr.isatty():
            print(f"\r{name} = {value:g} ({i}/{n})", end="", file=sys.stderr, flush=True)

    result = model.sweep(name, values, both_ways=args.both_ways, carry_state=args.carry_state,
                         settle=args.settle, measure=args.measure, method=args.method,
                         rtol=args.rtol, atol=args.atol, fintim=args.fintim,
                         progress=progress, **params)
    if not args.quiet:
        if sys.stderr.isatty():
            print(file=sys.stderr)
        sys.stdout.write(result.format())
        for direction, (a, b) in result.jumps().items():
            print(f"largest {'rise' if direction == 'up' else 'fall'} sweeping {direction}: "
                  f"between {name} = {a:g} and {b:g}")
    stem = os.path.splitext(os.path.basename(args.file))[0]
    out_dir = args.out or os.path.dirname(os.path.abspath(args.file))
    if args.csv:
        atomic_write(args.csv, result.csv_text().encode("utf-8"))
    if args.plot:
        path = plot_sweep(result, os.path.join(out_dir, f"{stem}_sweep.png"))
        if not args.quiet:
            print(f"written: {path}")
    failed = [p for p in result.points if p.status == "failed"]
    if failed:
        print(f"amilpy: {args.file}: the run at {name} = {failed[0].value:g} failed; the "
              "sweep stopped there", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK


def cmd_report(args) -> int:
    from .report import FORMATS, make_report

    formats = [f.strip().lower() for f in args.format.split(",") if f.strip()]
    bad = [f for f in formats if f not in FORMATS]
    if bad or not formats:
        raise _Usage(f"--format takes {', '.join(FORMATS)}; got {args.format!r}")
    written = make_report(args.file, args.out, formats, method=args.method,
                          **_parse_sets(args.set))
    for fmt, path in written.items():
        print(f"{fmt}: {path}")
    return EXIT_OK


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse has printed the usage
        return int(exc.code) if isinstance(exc.code, int) else EXIT_USAGE
    try:
        if args.command == "check":
            return cmd_check(args)
        if args.command == "sweep":
            return cmd_sweep(args)
        if args.command == "report":
            return cmd_report(args)
        return cmd_run(args)
    except _Usage as exc:
        print(f"amilpy: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except AmilError as exc:
        print(exc.render(), file=sys.stderr)
        return EXIT_MODEL
    except KeyboardInterrupt:
        print("amilpy: interrupted", file=sys.stderr)
        return EXIT_FAILED
    except BrokenPipeError:
        return EXIT_OK
    except MemoryError:
        print("amilpy: out of memory", file=sys.stderr)
        return EXIT_FAILED
    except RecursionError:
        print("amilpy: the listing is nested too deeply", file=sys.stderr)
        return EXIT_MODEL


if __name__ == "__main__":
    sys.exit(main())
