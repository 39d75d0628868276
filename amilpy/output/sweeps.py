"""A sweep for a reader: its table, its jumps in words, its CSV and its plot."""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence

from ..batch.sweep import SIDE, Sweep
from . import words as W
from .plot import literal_text, save_figure


def units(model, result: Sweep) -> tuple[str, str]:
    """The units of the swept value (its `!` comment) and of the measured variable
    (an OUTPUT LABEL's bracket, else its `!` comment)."""
    notes = W.name_notes(model.ir)
    labels = [r.label for r in model.ir.runs[0].reports
              if r.kind == "OUTPUT" and result.measure in r.names]
    measured = W.unit_of([result.measure], labels[0] if labels else None, notes)
    return notes.get(result.name, ("", ""))[0], measured


def table_text(result: Sweep) -> str:
    second = result.second
    head = (f"{'':6}{result.name:>14}" + (f"{second:>14}" if second else "") +
            f"{'MIN ' + result.measure:>16}{'MAX ' + result.measure:>16}{'HALF P-P':>16}")
    what = result.name + (f" AND {second}" if second else "")
    rows = [f"SWEEP OF {what}, {result.measure} MEASURED AFTER {result.settle:g} S", head]
    for p in result.points:
        rows.append(f"{p.direction:6}{p.value:14.6g}" +
                    (f"{p.second:14.6g}" if second else "") +
                    f"{p.minimum:16.6E}{p.maximum:16.6E}"
                    f"{p.amplitude:16.6E}" + ("" if p.status != "failed" else "  FAILED"))
    return "\n".join(rows) + "\n"


def jump_lines(result: Sweep) -> list[str]:
    """The jumps in words, each with its sign and how far it stands out; why the
    first point is left out, when it is."""
    out = []
    name = result.name
    if result.second is not None:
        return ["a grid of two data values: no jump search (it follows one swept value)"]
    if result.carry_state and result.points:
        out.append(f"the first point ({name} = {result.points[0].value:g}) starts from the "
                   "listing's initial state, a transient: it is left out of the jump search")
    jumps = result.jumps()
    for direction in dict.fromkeys(p.direction for p in result.points):
        if direction not in jumps:
            out.append(f"sweeping {direction}: too few points to tell a jump (it takes "
                       f"{2 * SIDE}, so that a step can be set against the trend of "
                       f"{SIDE} points on each side)")
            continue
        if not jumps[direction]:
            out.append(f"no jump sweeping {direction}: every step of HALF P-P follows the "
                       f"trend of the {SIDE} points on one side or the other (the first "
                       f"and last {SIDE - 1} steps are not judged)")
        for jump in jumps[direction]:
            what = f"{'up' if jump.rise else 'down'} sweeping {direction}: between " \
                f"{name} = {jump.start:g} and {jump.stop:g}, HALF P-P {jump.before:.4g} -> " \
                f"{jump.after:.4g} ({jump.ratio:.3g} times what the trends on both sides " \
                "miss by)"
            if hysteresis(result, jump):
                out.append(f"jump {what}")
            else:
                # (a linear oscillator's resonance, sampled coarser than its width, looks
                # the same: only the other way's branch, or a finer sweep, tells)
                why = "the sweep back, carrying the state, does not differ there" \
                    if result.carry_state and len(jumps) == 2 else \
                    "a sweep of independent points, or one way, cannot tell"
                out.append(f"steep step {what}: a jump, or a peak narrower than the step "
                           f"({why}); sweep finer between {jump.start:g} and "
                           f"{jump.stop:g}, or with --carry-state --both-ways, to tell")
    return out


def hysteresis(result: Sweep, jump) -> bool:
    """Whether the sweep the other way, carrying the state, stands on another branch at
    either end of the step: a jump with its hysteresis. A sweep that does not carry the
    state both ways cannot tell a jump from a peak narrower than the step."""
    if not result.carry_state:
        return False
    other = {p.value: p.amplitude for p in
             result.along("down" if jump.direction == "up" else "up")}
    mine = {p.value: p.amplitude for p in result.along(jump.direction)}
    for value in (jump.start, jump.stop):
        if value in other and value in mine and \
                abs(other[value] - mine[value]) > 1e-3 * max(abs(mine[value]), 1e-300):
            return True
    return False


def format_sweep(result: Sweep) -> str:
    return table_text(result) + "".join(line + "\n" for line in jump_lines(result))


def csv_rows(result: Sweep) -> tuple[list[str], Iterator[list]]:
    m = result.measure
    second = [result.second] if result.second else []
    # (DRIFT: how much HALF_PP moved between the two halves of the settled window, the
    # noise the jump search sets each step against; large: the point had not settled)
    header = ["DIRECTION", result.name, *second, f"MIN_{m}", f"MAX_{m}", f"HALF_PP_{m}",
              "STATUS", "TIME_START", "TIME_END", f"HALF_PP_DRIFT_{m}"]
    rows = ([p.direction, p.value, *([p.second] if second else []), p.minimum, p.maximum,
             p.amplitude, p.status, p.t_start, p.t_end, p.unsteady] for p in result.points)
    return header, rows


@literal_text
def plot_sweep(result: Sweep, path: str, title: str | None = None,
               axis_units: tuple[str, str] = ("", ""), formats: Sequence[str] = ()
               ) -> list[str]:
    """The characteristic, saved as `path` (or in each of `formats` beside it): the
    paths written."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 4.8))
    ax = fig.subplots()
    styles = {"sweep up": ("tab:blue", "^"), "sweep down": ("tab:red", "v")}
    for label, v, a in result.lines():
        colour, marker = styles.get(label, (None, "o"))
        if len(v):
            ax.plot(v, a, color=colour, marker=marker, markersize=4, linewidth=1.2,
                    label=label)
    x_unit, y_unit = axis_units
    ax.set_xlabel(result.name + (f" [{x_unit}]" if x_unit else ""))
    ax.set_ylabel(f"half peak-to-peak of {result.measure}" + (f" [{y_unit}]" if y_unit else ""))
    ax.set_title(W.shorten(title or f"{result.measure} against {result.name}", 90),
                 fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    return save_figure(fig, path, formats)


def sweep_figure_stem(out_dir: str, stem: str) -> str:
    """Where the sweep's figure goes, without its extension (one per --format)."""
    return os.path.join(out_dir, f"{stem}_sweep")
