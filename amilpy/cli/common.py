"""What the command line's commands share: exit codes, option values checked as
argparse reads them, the options several commands take, and the writing of their
outputs (`write_outputs`, `finish`). Standard library only at import, as the
parser is built before anything is run."""

from __future__ import annotations

import argparse
import math
import os
import sys

from ..diagnostics import UsageError
from ..language import fortran_float
from ..output.files import OutputError
from ..output.options import DIALECTS, Outputs, PlotOptions
from ..output.writers import dest, writers_for
from ..routes import method_names, route_for
from .console import Signals, write_out

EXIT_OK, EXIT_MODEL, EXIT_USAGE, EXIT_FAILED, EXIT_OUTPUT = 0, 1, 2, 3, 4


# ------------------------------------------------------------- value checks


def number(text: str) -> float:
    try:
        return fortran_float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def checked(kind: str, test, cast=number):
    def parse(text: str):
        value = cast(text)
        if not (math.isfinite(value) and test(value)):
            raise argparse.ArgumentTypeError(f"must be {kind}, got {text!r}")
        return value

    parse.__name__ = kind
    return parse


def integer(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None


POSITIVE = checked("a positive number", lambda x: x > 0)
NONNEGATIVE = checked("a number >= 0", lambda x: x >= 0)
FINITE = checked("a finite number", lambda x: True)
COUNT = checked("a whole number >= 1", lambda x: x >= 1, integer)


def method_name(text: str) -> str:
    if route_for(text) is None:
        raise argparse.ArgumentTypeError(
            f"unknown method {text!r}; the methods are {', '.join(method_names())}")
    return text.upper()


def figure_formats(text: str) -> tuple[str, ...]:
    from ..output.plot import FIGURE_FORMATS

    formats = tuple(dict.fromkeys(f.strip().lower() for f in text.split(",") if f.strip()))
    bad = [f for f in formats if f not in FIGURE_FORMATS]
    if bad or not formats:
        raise argparse.ArgumentTypeError(f"takes figure formats like png,svg,pdf (of "
                                         f"{', '.join(FIGURE_FORMATS)}), got {text!r}")
    return formats


def variable_names(text: str) -> tuple[str, ...]:
    names = tuple(dict.fromkeys(n.strip().upper() for n in text.split(",") if n.strip()))
    if not names:
        raise argparse.ArgumentTypeError(f"takes variable names like W1,MC, got {text!r}")
    return names


def run_numbers(text: str) -> tuple[int, ...]:
    try:
        numbers = tuple(int(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"takes run numbers like 1,3, got {text!r}") from None
    if not numbers or min(numbers) < 1:
        raise argparse.ArgumentTypeError(f"run numbers start at 1, got {text!r}")
    return numbers


def format_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--format", dest="figure_formats", type=figure_formats, metavar="LIST",
                   help="the figures' files, comma-separated of png, svg, pdf (vector: "
                        "for a printed report); implies --plot (default png)")


def writer_options(p: argparse.ArgumentParser, command: str) -> None:
    for w in writers_for(command):
        if w.flag is None:
            continue
        if w.takes_path:
            p.add_argument(w.flag, dest=dest(w.flag), metavar="PATH", help=w.help)
        else:
            p.add_argument(w.flag, dest=dest(w.flag), action="store_true", help=w.help)


def csv_dialect(p: argparse.ArgumentParser) -> None:
    p.add_argument("--csv-dialect", choices=list(DIALECTS), default="plain",
                   help="; ".join(f"{k}: {d.help}" for k, d in DIALECTS.items()))


def parse_sets(items: list[str], option: str = "--set") -> dict[str, float]:
    out = {}
    for item in items:
        if "=" not in item:
            raise UsageError(f"{option} takes NAME=VALUE, got {item!r}")
        name, value = item.split("=", 1)
        try:
            number = fortran_float(value)
        except ValueError:
            comma = "," in value and value.replace(",", ".", 1).replace(".", "", 1).isdigit()
            raise UsageError(f"{option} {name}: {value!r} is not a number" + (
                f"; the decimal separator is a point: {value.replace(',', '.', 1)}"
                if comma else "")) from None
        if not math.isfinite(number):
            raise UsageError(f"{option} {name}: the value must be finite, got {value!r}")
        out[name.strip().upper()] = number
    return out


def figure_options(args) -> PlotOptions:
    """The figure options of a command without a time window (sweep, the analyses)."""
    return PlotOptions(formats=getattr(args, "figure_formats", None) or ("png",))


def write_outputs(outputs: Outputs, args, signals: Signals,
                   skip: tuple[str, ...] = ()) -> tuple[list[str], list[str]]:
    """Every writer asked for (less those named in `skip`), each on its own: (paths
    written, error messages)."""
    written: list[str] = []
    errors: list[str] = []
    with signals.held():
        for w in writers_for(outputs.command):
            path = getattr(args, dest(w.flag), None) if w.flag else None
            asked = (w.wanted(outputs) if w.wanted else bool(path))
            if not asked or w.name in skip:
                continue
            try:
                written.extend(w.write(outputs, path if isinstance(path, str) else None))
            except OutputError as exc:
                if str(exc) not in errors:
                    errors.append(str(exc))
    return written, errors


def written_and_printed(command: str, path: str, model, result, args, signals, text) -> int:
    """An analysis's or an ensemble's files (the writers of `command`), then its
    printout `text(result, model)`; the exit code of the outputs."""
    stem, out_dir = stem_and_dir(path, getattr(args, "out", None))
    outputs = Outputs(command, stem, out_dir, model=model, analysis=result,
                      dialect=args.csv_dialect, plot=figure_options(args))
    written, errors = write_outputs(outputs, args, signals)
    if not args.quiet and not signals.held_back:
        write_out(lambda out: out.write(text(result, model)))
    return finish(path, written, errors, args.quiet, signals)


def stem_and_dir(path: str, out: str | None) -> tuple[str, str]:
    return (os.path.splitext(os.path.basename(path))[0],
            out or os.path.dirname(os.path.abspath(path)))


def finish(path: str, written: list[str], errors: list[str], quiet: bool,
            signals: Signals) -> int:
    """Say what was written and what was not; the exit code of the outputs."""
    if written and not quiet:
        write_out(lambda out: out.write("\nwritten: " + ", ".join(written) + "\n"))
    for message in errors:
        print(f"amilpy: {message}", file=sys.stderr)
    if signals.held_back:
        print(f"amilpy: {path}: {signals.name(signals.held_back)} held back until the "
              "files were complete; stopped", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OUTPUT if errors else EXIT_OK
