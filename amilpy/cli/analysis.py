"""The command line's analyses: `amilpy modes`, `periodic` and `response`
(amilpy.analysis computes, amilpy.output.analysis prints and draws). Options,
exit codes and the order of things (files first, then the printout) are those
of `amilpy.cli`; a periodic orbit Newton cannot find, an integration that cannot
go on, or a curve that cannot be followed over the whole range, is exit 3 with
what was found."""

from __future__ import annotations

import argparse
import math
import sys

from ..language import fortran_float, given_name
from . import common as base
from .console import Progress


def _span(text: str) -> tuple[str, float, float]:
    """NAME=START:STOP -> (NAME, START, STOP)."""
    try:
        name, spec = text.split("=", 1)
        start, stop = (fortran_float(x) for x in spec.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"write the range NAME=START:STOP, e.g. W=67.5:73, got {text!r}") from None
    if given_name(name) is None:
        raise argparse.ArgumentTypeError(f"{name.strip()!r} is not a name (NAME=START:STOP)")
    if not (math.isfinite(start) and math.isfinite(stop)) or start == stop:
        raise argparse.ArgumentTypeError(f"START and STOP must be finite and differ, got "
                                         f"{text!r}")
    return given_name(name), start, stop


def _angle(text: str) -> str:
    if "=" not in text or given_name(text.split("=", 1)[0]) is None:
        raise argparse.ArgumentTypeError(f"takes NAME=VALUE, e.g. PHI=2*PI, got {text!r}")
    return text


def _common(p: argparse.ArgumentParser, command: str, closure: bool = True) -> None:
    """The options every analysis takes."""
    p.add_argument("file", metavar="FILE", help="the listing (.amil)")
    if closure:
        group = p.add_mutually_exclusive_group(required=True)
        group.add_argument("--period", metavar="EXPR",
                           help="forced motion of known period: a number or an expression "
                                "of the listing's constants (2*PI/W)")
        group.add_argument("--angle", metavar="NAME=VALUE", type=_angle,
                           help="the period is over when state NAME has advanced by VALUE "
                                "(a crank angle, a forcing phase: PHI=2*PI)")
        p.add_argument("--settle", type=base.NONNEGATIVE, metavar="S",
                       help="settling run before Newton, seconds (default: FINTIM)")
        p.add_argument("--measure", metavar="VAR", action="append", default=[],
                       help="a variable measured over the period (repeatable; default: "
                            "the first OUTPUT/PRINT variable)")
        p.add_argument("--out", metavar="DIR", help="where the PNG goes (default: next to "
                                                    "the listing)")
    base.writer_options(p, command)
    base.csv_dialect(p)
    if closure:  # (modes draws nothing)
        base.format_option(p)
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[],
                   help="override a PARAM/CONST/INCON value (repeatable)")
    p.add_argument("--method", metavar="NAME", type=base.method_name,
                   help="integration method (default: the listing's METHOD, else DOP853, "
                        "or AUTO when that finds the model stiff)")
    p.add_argument("--rtol", type=base.POSITIVE, metavar="X",
                   help="relative tolerance (default 1e-9 for periodic and response)")
    p.add_argument("--atol", type=base.POSITIVE, metavar="X",
                   help="absolute tolerance (default 1e-12 for periodic and response)")
    p.add_argument("--max-time", type=base.POSITIVE, metavar="S",
                   help="wall-clock limit of the whole analysis, seconds (a response curve "
                        "keeps the points found by then)")
    p.add_argument("--quiet", action="store_true", help="no printout, only files and errors")


def add_parsers(sub) -> None:
    m = sub.add_parser("modes", help="linear modes: eigenvalues, natural frequencies, "
                                     "damping ratios and shapes about a state")
    _common(m, "modes", closure=False)
    m.add_argument("--at", type=base.FINITE, default=0.0, metavar="TIME",
                   help="linearise about the state the run reaches at this TIME (default 0: "
                        "its initial state)")
    p = sub.add_parser("periodic", help="the periodic steady state by shooting: period, "
                                        "extremes, Floquet multipliers, stability")
    _common(p, "periodic")
    r = sub.add_parser("response", help="a response curve by continuation of the periodic "
                                        "orbit: stable and unstable branches, folds")
    _common(r, "response")
    r.add_argument("span", metavar="NAME=START:STOP", type=_span,
                   help="the data value followed and its range")
    add_fit_parser(sub)
    add_steady_parser(sub)


def add_steady_parser(sub) -> None:
    s = sub.add_parser("steady", help="the equilibrium (every derivative zero) in the "
                                      "switch branches that hold there: states, "
                                      "eigenvalues, stability; the linear model A, B, C, "
                                      "D and its Bode diagram")
    _common(s, "steady", closure=False)
    base.format_option(s)
    s.add_argument("--at", type=base.FINITE, default=None, metavar="TIME",
                   help="freeze the field at this TIME (what TIME drives: a STEP, a "
                        "forcing; default the run's start)")
    s.add_argument("--guess", metavar="NAME=VALUE", action="append", default=[],
                   help="start the search with state NAME at VALUE (repeatable; default "
                        "the listing's initial values)")
    s.add_argument("--linear", action="store_true",
                   help="print the linear model A, B, C, D about the equilibrium (with "
                        "--input and --output; giving them is enough)")
    s.add_argument("--input", metavar="NAME", action="append", default=[],
                   help="a data value (PARAM/CONST/INCON) taken as an input u of the "
                        "linear model (repeatable)")
    s.add_argument("--output", metavar="NAME", action="append", default=[],
                   help="a variable taken as an output y of the linear model "
                        "(repeatable)")
    s.add_argument("--out", metavar="DIR", help="where the Bode PNGs go (default: next "
                                                "to the listing)")


def cmd_steady(args, path: str, signals) -> int:
    from ..output.steady import steady_text

    if (args.linear or args.matrices or args.bode) and not (args.input and args.output):
        print(f"amilpy: {path}: --linear, --matrices and --bode need the linear model: give "
              "--input NAME (a data value) and --output NAME (a variable)", file=sys.stderr)
        return base.EXIT_USAGE
    model, params = _prepare(args, path)
    guess = base.parse_sets(args.guess, "--guess")
    result, code = _computed(args, path, lambda progress: model.steady(
        at=args.at, guess=guess, inputs=args.input, outputs=args.output,
        method=args.method, rtol=args.rtol, atol=args.atol, progress=progress,
        max_time=args.max_time, **params), prefix="steady: ")
    if code is not None:
        return code
    return base.written_and_printed("steady", path, model, result, args, signals, steady_text)


def add_fit_parser(sub) -> None:
    f = sub.add_parser("fit", help="fit data values to measurements: weighted least "
                                   "squares, estimates with standard errors and 95 %% "
                                   "intervals")
    f.add_argument("file", metavar="FILE", help="the listing (.amil)")
    f.add_argument("--data", metavar="OBS.csv", required=True,
                   help="the observations: TIME and variables' columns, optional "
                        "SD_<NAME> and RUN (as run --data)")
    f.add_argument("--free", metavar="NAME[=LO:HI]", action="append", required=True,
                   help="a PARAM/CONST/INCON value to fit, with bounds (repeatable)")
    f.add_argument("--log", metavar="NAME", action="append", default=[],
                   help="fit this one on a log scale (a positive rate, a time constant)")
    f.add_argument("--weights", choices=("sd", "relative", "none"), default=None,
                   help="residuals divided by the SD_<NAME> columns (default when the "
                        "file has them), by |observed|, or as they are (default otherwise)")
    f.add_argument("--gradients", choices=("differences", "sensitivities"),
                   default="differences",
                   help="the Jacobian: central differences of whole runs (default), or the "
                        "variational equations with their jumps at the switches (exact; "
                        "differences where they do not apply, saying why)")
    f.add_argument("--max-evaluations", type=base.COUNT, default=200, metavar="N",
                   help="evaluations of the runs the optimiser may make (default 200)")
    f.add_argument("--out", metavar="DIR", help="where the PNGs go (default: next to the "
                                                "listing)")
    base.writer_options(f, "fit")
    base.csv_dialect(f)
    base.format_option(f)
    f.add_argument("--set", metavar="NAME=VALUE", action="append", default=[],
                   help="override a PARAM/CONST/INCON value (repeatable)")
    f.add_argument("--method", metavar="NAME", type=base.method_name,
                   help="integration method (default: the listing's METHOD)")
    f.add_argument("--rtol", type=base.POSITIVE, metavar="X", help="relative tolerance")
    f.add_argument("--atol", type=base.POSITIVE, metavar="X", help="absolute tolerance")
    f.add_argument("--quiet", action="store_true", help="no printout, only files and errors")


def cmd_fit(args, path: str, signals) -> int:
    from ..observed import read
    from ..output.fitting import fit_text

    model, params = _prepare(args, path)
    obs = read(args.data, model.ir.variables, len(model.ir.runs))
    weights = args.weights or ("sd" if all(s.sd is not None for s in obs.series)
                               else "none")
    progress = Progress(not args.quiet)
    try:
        result = model.fit(obs, args.free, log=args.log, weights=weights,
                           method=args.method, rtol=args.rtol, atol=args.atol,
                           progress=progress, max_evaluations=args.max_evaluations,
                           gradients=args.gradients, **params)
    finally:
        progress.done()
    code = base.written_and_printed("fit", path, model, result, args, signals, fit_text)
    if not result.success:
        print(f"amilpy: {path}: the fit did not converge: {result.message}", file=sys.stderr)
        code = max(code, base.EXIT_FAILED)
    return code


def _prepare(args, path: str):
    from ..api import load

    model = load(path)
    return model, base.parse_sets(args.set)  # (the API checks the names)


def _computed(args, path: str, compute, not_found: str = "", prefix: str = ""):
    """(compute(progress)'s result, None) with the progress line shown meanwhile, or
    (None, the exit code) when the flow failed or, where `not_found` says how to put
    it, no periodic orbit was found."""
    from ..analysis import NotConverged
    from ..run.flow import FlowFailed  # (here: `check` builds these parsers, runs nothing)

    progress = Progress(not args.quiet)
    progress.prefix = prefix
    try:
        return compute(progress), None
    except NotConverged as exc:
        if not not_found:
            raise
        print(f"amilpy: {path}: {not_found}: {exc}", file=sys.stderr)
        return None, base.EXIT_FAILED
    except FlowFailed as exc:
        print(f"amilpy: {path}: {exc}", file=sys.stderr)
        return None, base.EXIT_FAILED
    finally:
        progress.done()


def cmd_modes(args, path: str, signals) -> int:
    from ..output.analysis import modes_text

    model, params = _prepare(args, path)
    result, code = _computed(args, path, lambda progress: model.modes(
        at=args.at, method=args.method, rtol=args.rtol, atol=args.atol, progress=progress,
        max_time=args.max_time, **params), prefix=f"modes: to TIME = {args.at:g}  ")
    if code is not None:
        return code
    return base.written_and_printed("modes", path, model, result, args, signals, modes_text)


def cmd_periodic(args, path: str, signals) -> int:
    from ..output.analysis import orbit_text

    model, params = _prepare(args, path)
    orbit, code = _computed(args, path, lambda progress: model.periodic(
        period=args.period, angle=args.angle, measure=args.measure, settle=args.settle,
        method=args.method, rtol=args.rtol, atol=args.atol, progress=progress,
        max_time=args.max_time, **params), not_found="no periodic orbit found")
    if code is not None:
        return code
    return base.written_and_printed("periodic", path, model, orbit, args, signals, orbit_text)


def cmd_response(args, path: str, signals) -> int:
    from ..output.analysis import response_text

    name, start, stop = args.span
    model, params = _prepare(args, path)
    resp, code = _computed(args, path, lambda progress: model.response(
        name, start, stop, period=args.period, angle=args.angle, measure=args.measure,
        settle=args.settle, method=args.method, rtol=args.rtol, atol=args.atol,
        progress=progress, max_time=args.max_time, **params),
        not_found=f"no periodic orbit at {name} = {start:g}")
    if code is not None:
        return code
    code = base.written_and_printed("response", path, model, resp, args, signals, response_text)
    if resp.interrupted or resp.timed_out:
        why = "interrupted" if resp.interrupted else \
            f"stopped at --max-time {args.max_time:g} s"
        print(f"amilpy: {path}: {why} after {name} = {resp.points[-1].value:.7g}; "
              "what was found is printed and written", file=sys.stderr)
        code = max(code, base.EXIT_FAILED)
    elif not resp.complete:
        print(f"amilpy: {path}: the curve could not be followed past {name} = "
              f"{resp.points[-1].value:.7g}; what was found is printed and written",
              file=sys.stderr)
        code = max(code, base.EXIT_FAILED)
    return code


COMMANDS = {"modes": cmd_modes, "periodic": cmd_periodic, "response": cmd_response,
            "fit": cmd_fit, "steady": cmd_steady}
