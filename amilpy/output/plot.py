"""Runs -> figures: one per OUTPUT statement, the runs overlaid.

Each run has its colour and each variable its line style; the legend names the
runs by the data values that tell them apart (run 1's included). Variables whose
scales differ by more than `SCALE_RATIO` get an axis each. The y axis takes its
unit from the LABEL ("... [RAD/S]"), TIME is in seconds. `OUTPUT Y1, Y2 VS X`
plots against X. A time window (`PlotOptions.start/stop`) and a zoomed figure
around the first switching event (`zoom_events`) show a transient.

matplotlib is imported here only, and only when a figure is drawn; figures are
saved without pyplot, so saving never touches the user's backend.
"""

from __future__ import annotations

import functools
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..result import EventKind, Run
from . import words as W
from .files import atomic_write
from .options import PlotOptions
from .tables import report_names

SCALE_RATIO = 100.0  # variables further apart than this get an axis each
STYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1, 1, 1)), (0, (1, 3)), (0, (8, 2)))
TITLE_CHARS = 90  # a longer TITLE/LABEL is shortened in the plot (not in the printout)
# what `--format` offers for figures: PNG for a quick look and a word processor,
# SVG and PDF (vector) for a report that is printed or zoomed
FIGURE_FORMATS = ("png", "svg", "pdf")
STARTUP = 1e-3  # events in this fraction of the run are start-up, not a transient
EVENT_KINDS = (EventKind.SWITCH, EventKind.BREAKPOINT, EventKind.LEVEL, EventKind.SLIDE)


@dataclass(frozen=True)
class FigureSpec:
    names: tuple[str, ...]
    label: str | None
    x: str | None = None  # None: against TIME
    window: tuple[float, float] | None = None
    zoom: bool = False


def figure_specs(run: Run) -> list[FigureSpec]:
    """One figure per OUTPUT statement; without one, the PRINT variables (or the
    first six) against TIME."""
    specs = [FigureSpec(tuple(n for n in r.names if n != "TIME"), r.label,
                        getattr(r, "x", None))
             for r in run.reports if r.kind == "OUTPUT"]
    if not specs:
        names = report_names(run, "PRINT") or [n for n in run.values if "#" not in n][:6]
        specs = [FigureSpec(tuple(n for n in names if n != "TIME"), None)]
    return specs


def zoom_window(run: Run) -> tuple[float, float] | None:
    """Around the first switching event after start-up: a tenth of the window
    before it, then the burst of events that follows it (each within 5 % of the
    run of the last) four times over, at least 1 % of the run."""
    t0, t1 = float(run.times[0]), float(run.t_end or run.times[-1])
    length = t1 - t0
    if length <= 0:
        return None
    times = [e.time for e in run.events if e.kind in EVENT_KINDS
             and e.time > t0 + STARTUP * length]
    if not times:
        return None
    first = last = times[0]
    for t in times[1:]:
        if t - last > 0.05 * length:
            break
        last = t
    width = max(4.0 * (last - first), 0.01 * length)
    return max(t0, first - 0.1 * width), min(t1, first + width)


# ------------------------------------------------------------------ drawing


def literal_text(drawing):
    """Every text a figure takes from a listing (TITLE, LABEL, units, names) is
    drawn as written. A `$` would start matplotlib's mathtext: a stray
    `$\\sqrt{` failed the whole plot with a ValueError, a well-formed one drew a
    formula the author did not write, and `text.usetex` would hand it to TeX."""
    @functools.wraps(drawing)
    def literally(*args, **kwargs):
        import matplotlib

        with matplotlib.rc_context({"text.parse_math": False, "text.usetex": False}):
            return drawing(*args, **kwargs)
    return literally


def _figure(show: bool, **kw):
    if show:
        import matplotlib.pyplot as plt

        return plt.figure(**kw)
    from matplotlib.figure import Figure

    return Figure(**kw)


def _window_index(t: np.ndarray, window: tuple[float, float] | None) -> slice:
    """The rows inside the window, with one more each side so lines reach its edges."""
    if window is None:
        return slice(None)
    a = max(int(np.searchsorted(t, window[0], "left")) - 1, 0)
    b = int(np.searchsorted(t, window[1], "right")) + 1
    return slice(a, b)


def _scale(values: list[np.ndarray]) -> float:
    finite = [np.nanmax(np.abs(v)) for v in values if v.size and np.isfinite(v).any()]
    return float(max(finite)) if finite else 0.0


# Past this, matplotlib's tick arithmetic overflows (a range of 2 * 1.7E308 is not a
# float): such an axis is drawn in units of a power of ten, named in its label.
HUGE = 1e300


def _factor(scale: float) -> float:
    """The power of ten an axis whose largest |value| is `scale` is drawn in (1 for
    any ordinary axis)."""
    return 1.0 if not scale >= HUGE else 10.0 ** math.floor(math.log10(scale))


def _in_units(factor: float) -> str:
    return "" if factor == 1.0 else f" (x 1E{round(math.log10(factor))})"


def _axis_groups(names: Sequence[str], scales: dict[str, float], subplots: bool
                 ) -> list[list[str]]:
    """All variables on one axis, unless asked or their scales differ by more than
    SCALE_RATIO (variables that are zero throughout fit any axis)."""
    if subplots:
        return [[n] for n in names]
    sized = [s for s in scales.values() if s > 0]
    if len(sized) > 1 and max(sized) > SCALE_RATIO * min(sized):
        return [[n] for n in names]
    return [list(names)]


@literal_text
def draw(runs: Sequence[Run], spec: FigureSpec, labels: Sequence[str] | None = None,
         notes: dict[str, tuple[str, str]] | None = None, subplots: bool = False,
         show: bool = False, numbers: Sequence[int] | None = None, into=None,
         height: float = 4.8):
    """One figure of `spec` over `runs` (a matplotlib Figure), `height` inches tall
    with one axis; `into`: a Figure or SubFigure to draw in instead (a report's
    page), its margins set in inches."""
    from matplotlib.lines import Line2D

    notes = notes or {}
    labels = list(labels) if labels is not None else W.run_labels(runs)
    numbers = list(numbers) if numbers is not None else list(range(1, len(runs) + 1))
    names = [n for n in spec.names if any(n in r for r in runs)]
    data: dict[tuple[int, str], tuple[np.ndarray, np.ndarray]] = {}
    for k, run in enumerate(runs):
        if spec.x is not None and spec.x not in run:
            continue  # (another listing's run, overlaid, without the X variable)
        # (every recorded row, not the OUTDEL grid's alone: a crossing's instant is one,
        # where a bouncing ball touches the floor between two grid rows)
        xs = run.times if spec.x is None else run.sample(spec.x)[1]
        part = _window_index(run.times, spec.window)
        for n in names:
            if n in run:
                data[k, n] = (np.asarray(xs[part], float),
                              np.asarray(run.sample(n)[1][part], float))
    scales = {n: _scale([v for (k, m), (_, v) in data.items() if m == n]) for n in names}
    groups = _axis_groups(names, scales, subplots)
    fig = into if into is not None else _figure(show, figsize=figure_size(len(groups), height))
    axes = fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0]
    several = len(runs) > 1
    style = {n: STYLES[i % len(STYLES)] for i, n in enumerate(names)}
    # (TIME is not scaled: the window and the event lines are in TIME)
    x_factor = 1.0 if spec.x is None else _factor(_scale([x for x, _ in data.values()]))
    for ax, group in zip(axes, groups, strict=True):
        factor = _factor(max((scales[n] for n in group), default=0.0))
        for k in range(len(runs)):
            for n in group:
                if (k, n) not in data:
                    continue
                x, y = data[k, n][0] / x_factor, data[k, n][1] / factor
                colour = f"C{(numbers[k] - 1) % 10}" if several else f"C{names.index(n) % 10}"
                ax.plot(x, y, color=colour, linestyle=style[n], linewidth=1.2,
                        label=n if not several else f"{n}, {labels[k]}")
                if spec.x is None:
                    _mark_observed(ax, runs[k], n, spec.window, factor, colour,
                                   n if not several else f"{n}, {labels[k]}")
        unit = W.unit_of(group, spec.label, notes)
        ax.set_ylabel(W.shorten(", ".join(group), 40) + (f" [{unit}]" if unit else "")
                      + _in_units(factor))
        ax.grid(True, alpha=0.3)
        if spec.window is not None and spec.x is None:
            ax.set_xlim(*spec.window)
        _mark_events(ax, runs, spec)
        if several and len(group) > 1:
            runs_legend = ax.legend(
                [Line2D([], [], color=f"C{(numbers[k] - 1) % 10}") for k in range(len(runs))],
                labels, fontsize=8, loc="upper left", title=None)
            ax.add_artist(runs_legend)
            ax.legend([Line2D([], [], color="0.2", linestyle=style[n]) for n in group],
                      group, fontsize=8, loc="upper right")
        elif several:
            ax.legend([Line2D([], [], color=f"C{(numbers[k] - 1) % 10}", linestyle=style[group[0]])
                       for k in range(len(runs))], labels, fontsize=8)
        elif len(group) > 1 or any(c.name in group for r in runs for c in r.observed):
            ax.legend(fontsize=8)
    axes[-1].set_xlabel(_x_label(spec, notes) + _in_units(x_factor))
    title = spec.label or (runs[0].titles[0] if runs and runs[0].titles else ", ".join(names))
    if spec.zoom and spec.window is not None:
        title = f"{title} (TIME {spec.window[0]:.4g} to {spec.window[1]:.4g} s)"
    axes[0].set_title(W.shorten(title, TITLE_CHARS), fontsize=10)
    partial = [f"run {numbers[k]} partial: TIME = {r.t_end:.6g}" if several
               else f"partial: TIME = {r.t_end:.6g}" for k, r in enumerate(runs) if not r.ok]
    if partial:
        fig.text(0.99, 0.005, "; ".join(partial), ha="right", va="bottom", fontsize=7,
                 color="tab:red")
    if into is None:
        fig.tight_layout(rect=(0, 0.03 if partial else 0, 1, 1))
    else:  # (a SubFigure has no layout of its own: margins for the labels, in inches)
        w, h = (fig.bbox.width / fig.dpi, fig.bbox.height / fig.dpi)
        fig.subplots_adjust(left=0.8 / w, right=1 - 0.15 / w, bottom=0.5 / h,
                            top=1 - 0.3 / h, hspace=0.35 / (h / len(groups)))
    return fig


def _mark_observed(ax, run: Run, name: str, window, factor: float, colour: str,
                   label: str) -> None:
    """The observations of `name` (`--data`) as markers over its line, with their
    standard deviations as bars when the file gives them."""
    for c in run.observed:
        if c.name != name:
            continue
        keep = np.ones(len(c.t), bool) if window is None else \
            (c.t >= window[0]) & (c.t <= window[1])
        if not keep.any():
            continue
        ax.errorbar(c.t[keep], c.observed[keep] / factor,
                    yerr=None if c.sd is None else c.sd[keep] / factor, fmt="o",
                    markersize=4, color=colour, markerfacecolor="white", elinewidth=0.8,
                    capsize=2, label=f"{label} ({W.shorten(os.path.basename(c.source), 24)})")


def figure_size(axes: int, height: float = 4.8) -> tuple[float, float]:
    """A figure's size in inches with `axes` axes stacked (`height`: with one)."""
    return (8.0, height if axes == 1 else 1.2 + 1.9 * axes)


def _x_label(spec: FigureSpec, notes: dict[str, tuple[str, str]]) -> str:
    if spec.x is None:
        unit = notes.get("TIME", ("s", ""))[0]
        return "TIME" + (f" [{unit}]" if unit else "")
    unit = notes.get(spec.x, ("", ""))[0]
    return spec.x + (f" [{unit}]" if unit else "")


def _mark_events(ax, runs: Sequence[Run], spec: FigureSpec) -> None:
    """Thin lines at the switching instants: every event in a zoomed figure, the
    breakpoints of a single run otherwise."""
    if spec.x is not None or (len(runs) > 1 and not spec.zoom):
        return
    lo, hi = spec.window or (-math.inf, math.inf)
    kinds = EVENT_KINDS if spec.zoom else (EventKind.BREAKPOINT,)
    shown = sorted({e.time for e in runs[0].events[:2000] if e.kind in kinds
                    and lo <= e.time <= hi})[:200]
    for t in shown:
        ax.axvline(t, color="0.75", linewidth=0.6, linestyle=":" if spec.zoom else "-",
                   zorder=0)


# ------------------------------------------------------------------- files


def selected(runs: Sequence[Run], numbers: tuple[int, ...] | None
             ) -> tuple[list[Run], list[str], list[int]]:
    """The runs `--runs` chose, their legend labels (from all runs, so a label
    does not change with the choice) and their numbers."""
    labels = W.run_labels(runs)
    chosen = list(numbers) if numbers else list(range(1, len(runs) + 1))
    return [runs[k - 1] for k in chosen], [labels[k - 1] for k in chosen], chosen


def caption(spec: FigureSpec, runs: Sequence[Run], labels: Sequence[str],
            words: dict[str, str] | None = None) -> str:
    """What a figure shows, for a report: its LABEL (or TITLE), the variables
    against TIME or X, the window, and the runs."""
    words = words or W.WORDS["en"]
    base = spec.label or (runs[0].titles[0] if runs and runs[0].titles else "")
    what = f"{', '.join(spec.names)} {words['against']} {spec.x or 'TIME'}"
    text = f"{base}: {what}" if base else what
    if spec.window is not None:
        text += f", TIME {spec.window[0]:.4g} to {spec.window[1]:.4g} s"
    if len(runs) > 1:
        text += "; " + "; ".join(labels)
    return text


@dataclass(frozen=True)
class SavedFigure:
    """A figure as written: its files (one per format), its caption, and how to
    draw it again into another Figure or SubFigure (a report's page)."""

    paths: list[str]
    caption: str
    redraw: object  # Callable[[Figure | SubFigure], object]
    size: tuple[float, float]  # inches, as saved


def plot_figures(runs: list[Run], out_dir: str, stem: str,
                 options: PlotOptions | None = None,
                 notes: dict[str, tuple[str, str]] | None = None,
                 words: dict[str, str] | None = None) -> list[SavedFigure]:
    """Draw and save one figure per OUTPUT statement (and a zoomed one per statement
    with `zoom_events`), each in every one of `options.formats`: its files, caption
    and a way to draw it again (a report's page draws it as vector graphics)."""
    options = options or PlotOptions()
    chosen, labels, numbers = selected(runs, options.runs)
    return _save_specs(chosen, labels, numbers, figure_specs(runs[0]), out_dir, stem,
                       options, notes, words)


def window_suffix(window: tuple[float, float]) -> str:
    """What a windowed figure's file name adds, so `--from/--to` never replaces the
    whole run's figure: `_from_0.03_to_0.04`."""
    return f"_from_{window[0]:.6g}_to_{window[1]:.6g}"


def plot_overlay(listings: Sequence[tuple[str, Sequence[Run]]], out_dir: str,
                 options: PlotOptions | None = None,
                 notes: dict[str, tuple[str, str]] | None = None) -> list[str]:
    """Several listings' runs in the same figures (`amilpy run a.amil b.amil
    --overlay`): the first listing's OUTPUT statements, a colour per run, each named
    by its listing's file name (and, where a listing has several runs, by the values
    that tell them apart); a variable a listing lacks is left out for it. Saved as
    `A_vs_B` in each of `options.formats`: the paths written."""
    options = options or PlotOptions()
    runs: list[Run] = []
    labels: list[str] = []
    for stem, its_runs in listings:
        chosen, its_labels, _ = selected(its_runs, options.runs)
        runs += chosen
        labels += [stem if len(its_runs) == 1 else f"{stem}, {label}"
                   for label in its_labels]
    stem = "_vs_".join(s for s, _ in listings)
    return [path for f in
            _save_specs(runs, labels, list(range(1, len(runs) + 1)),
                        figure_specs(listings[0][1][0]), out_dir, stem, options, notes)
            for path in f.paths]


def _save_specs(chosen: list[Run], labels: list[str], numbers: list[int],
                specs: list[FigureSpec], out_dir: str, stem: str, options: PlotOptions,
                notes: dict[str, tuple[str, str]] | None = None,
                words: dict[str, str] | None = None) -> list[SavedFigure]:
    window = None
    if options.start is not None or options.stop is not None:
        t0 = min(float(r.times[0]) for r in chosen)
        t1 = max(float(r.t_end or r.times[-1]) for r in chosen)
        window = (t0 if options.start is None else options.start,
                  t1 if options.stop is None else options.stop)
    out = []
    for k, spec in enumerate(specs, start=1):
        stem_k = f"{stem}_{k}" if len(specs) > 1 else stem
        todo = [(replace(spec, window=window),
                 stem_k + (window_suffix(window) if window is not None else ""))]
        zoom = zoom_window(chosen[0]) if options.zoom_events and spec.x is None else None
        if zoom is not None:
            todo.append((replace(spec, window=zoom, zoom=True), f"{stem_k}_zoom"))
        for figure_spec, name in todo:
            fig = draw(chosen, figure_spec, labels, notes, options.subplots, options.show,
                       numbers, height=options.height)
            paths = save_figure(fig, os.path.join(out_dir, name), options.formats)
            redraw = functools.partial(draw, chosen, figure_spec, labels, notes,
                                       options.subplots, False, numbers,
                                       height=options.height)
            out.append(SavedFigure(paths, caption(figure_spec, chosen, labels, words), redraw,
                                   tuple(fig.get_size_inches())))
    if options.show:
        import matplotlib.pyplot as plt

        plt.show()
    return out


def plot_runs(runs: list[Run], out_dir: str, stem: str, options: PlotOptions | None = None,
              notes: dict[str, tuple[str, str]] | None = None) -> list[str]:
    """Every file `plot_figures` writes."""
    return [path for f in plot_figures(runs, out_dir, stem, options, notes)
            for path in f.paths]


def save_figure(fig, path: str, formats: Sequence[str] = ()) -> list[str]:
    """Save `fig` as `path` (its extension says the format), or, given `formats`, as
    the stem `path` with each format's extension; the paths written, in that order.
    Vector formats keep text as text (SVG: searchable; PDF: fonts embedded)."""
    if formats:  # (`path` is a stem: a listing's name may have dots, "lab.svg.amil")
        stem = path
    else:
        stem, ext = os.path.splitext(path)
        formats = (ext.lstrip(".").lower(),)
        if formats[0] not in FIGURE_FORMATS:  # (a dot that is no extension: "x_0.5")
            stem, formats = path, ("png",)
    import matplotlib

    out = []
    for fmt in formats:
        if fmt not in FIGURE_FORMATS:
            raise ValueError(f"figure format {fmt!r}; the formats are "
                             f"{', '.join(FIGURE_FORMATS)}")
        buf = io.BytesIO()
        # (SVG with its text as text, not paths: a report can search and restyle it;
        # no date in it, so the same figure is the same file)
        with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "amilpy"}):
            fig.savefig(buf, format=fmt, dpi=110,
                        metadata={"Date": None} if fmt == "svg" else
                        {"CreationDate": None} if fmt == "pdf" else None)
        target = f"{stem}.{fmt}"
        atomic_write(target, buf.getvalue())
        out.append(target)
    return out


def can_show() -> bool:
    """Whether windows can be opened: a display and an interactive backend that
    loads (with DISPLAY set but no GUI toolkit, matplotlib would fall back to Agg
    and warn on show)."""
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return False
    import matplotlib

    try:
        import matplotlib.pyplot as plt

        backend = plt.get_backend().lower()
    except Exception:  # a broken GUI toolkit: draw to files only
        return False
    interactive = {b.lower() for b in _interactive_backends(matplotlib)}
    return backend in interactive


def _interactive_backends(matplotlib) -> list[str]:
    try:
        from matplotlib.backends import BackendFilter, backend_registry

        return backend_registry.list_builtin(BackendFilter.INTERACTIVE)
    except ImportError:  # matplotlib < 3.9
        return list(matplotlib.rcsetup.interactive_bk)


# ---------------------------------------------------------------- notebooks


@literal_text
def plot_run(run: Run, names: Sequence[str], ax=None, label: str | None = None):
    """`Run.plot`: variables against TIME on `ax` (a new one if None). Lines are
    labelled by name, and by `label` (default: the run's own label unless it is
    just "RUN n"); for several runs, `draw_runs` labels them by their values."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(7, 4))
    if label is None and not (run.label.startswith("RUN ") and run.label[4:].isdigit()):
        label = run.label
    for name in names or [n for n in run.values if "#" not in n]:
        ax.plot(*run.sample(name), label=name.upper() + (f" ({label})" if label else ""))
    ax.set_xlabel("TIME [s]")
    # (the caller's axes made their title's text before: it is told too)
    ax.set_title(W.shorten(run.titles[0] if run.titles else run.label, TITLE_CHARS),
                 parse_math=False)
    ax.grid(True, alpha=0.3)
    ax.legend()
    return ax


def draw_runs(runs: Sequence[Run], *names: str, ax=None):
    """Several runs on one axes, each line labelled by variable and by the data
    values that tell its run from the others (run 1's included)."""
    for run, label in zip(runs, W.run_labels(runs), strict=True):
        ax = plot_run(run, names, ax, label or None)
    return ax
