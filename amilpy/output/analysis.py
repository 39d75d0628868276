"""The analyses for a reader: modes, a periodic orbit and a response curve as
printed tables, CSV rows and figures (`amilpy.analysis` computes them)."""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Sequence

import numpy as np

from ..run.jacobian import DIFFERENCES
from . import words as W
from .plot import literal_text, save_figure

ZERO_MODE = "zero (rigid-body or cyclic)"


def _num(x: float) -> str:
    return f"{x:14.6E}" if math.isfinite(x) else f"{'-':>14}"


def _component(c: complex, top: float) -> str:
    """A mode-shape component: real when its phase is 0 or 180 degrees to 1E-3, else
    |c|<phase in degrees."""
    if abs(c.imag) <= 1e-3 * max(abs(c), 1e-300) or abs(c) <= 1e-9 * top:
        return f"{c.real:.4g}"
    return f"{abs(c):.4g}<{math.degrees(math.atan2(c.imag, c.real)):.1f}"


def units(model, name: str | None, measure: str | None) -> tuple[str, str]:
    """The units of a data value (its ! comment) and of a measured variable (an
    OUTPUT LABEL's bracket, else its ! comment)."""
    if model is None:
        return "", ""
    notes = W.name_notes(model.ir)
    labels = [r.label for r in model.ir.runs[0].reports
              if r.kind == "OUTPUT" and measure in r.names]
    unit = W.unit_of([measure], labels[0] if labels else None, notes) if measure else ""
    return (notes.get(name, ("", ""))[0] if name else ""), unit


def _title(model) -> str:
    titles = model.ir.runs[0].titles if model is not None else []
    return titles[0] if titles else (model.name if model is not None else "")


# -------------------------------------------------------------------- modes

def modes_text(result, model=None) -> str:
    head = f"LINEAR MODES OF {_title(model)}".rstrip()
    lines = [head, f"about the state at TIME = {result.time:.9g}, switch branches as in force "
             "there; Jacobian from " + (result.how if result.how != DIFFERENCES
                                         else f"{DIFFERENCES}, estimated error "
                                         f"{result.error:.1E} of its largest entry"),
             "  " + ", ".join(f"{n} = {v:.6g}" for n, v in zip(result.names, result.state.y,
                                                               strict=True)), "",
             *eigen_table(result.modes)]
    lines += ["", "MODE SHAPES (largest component 1; a complex one as |c|<phase in degrees)",
              f"{'MODE':>5}" + "".join(f" {n:>13}" for n in result.names)]
    for k, m in enumerate(result.modes, 1):
        top = float(np.max(np.abs(m.shape))) if len(m.shape) else 0.0
        lines.append(f"{k:5d}" + "".join(f" {_component(c, top):>13}" for c in m.shape))
    return "\n".join(lines) + "\n"


def eigen_table(modes) -> list[str]:
    """The eigenvalue table's lines: RE, IM, WN, F, ZETA per mode."""
    lines = [f"{'MODE':>5}{'RE [1/S]':>14}{'IM [RAD/S]':>14}{'WN [RAD/S]':>14}"
             f"{'F [HZ]':>14}{'ZETA':>14}"]
    for k, m in enumerate(modes, 1):
        lam = m.eigenvalue
        if m.zero:
            lines.append(f"{k:5d}{_num(lam.real)}{_num(lam.imag)}  {ZERO_MODE}")
        else:
            lines.append(f"{k:5d}{_num(lam.real)}{_num(lam.imag)}{_num(m.wn)}{_num(m.fhz)}"
                         f"{_num(m.zeta)}")
    return lines


def modes_csv(result) -> tuple[list[str], Iterator[list]]:
    """RE, IM, WN, FHZ, ZETA, the shape's real part per state, then its imaginary
    part per state (IM_<state>)."""
    header = ["RE", "IM", "WN", "FHZ", "ZETA", *result.names,
              *(f"IM_{n}" for n in result.names)]
    rows = ([m.eigenvalue.real, m.eigenvalue.imag, m.wn, m.fhz, m.zeta,
             *(float(c.real) for c in m.shape), *(float(c.imag) for c in m.shape)]
            for m in result.modes)
    return header, rows


# ----------------------------------------------------------------- periodic

def _multipliers(mu: np.ndarray) -> str:
    parts = []
    for c in mu:
        if abs(c.imag) > 1e-9 * max(abs(c), 1e-300):
            if c.imag > 0:
                parts.append(f"{c.real:.6g} +- {c.imag:.6g}j (|mu| {abs(c):.6g})")
        else:
            parts.append(f"{c.real:.6g}")
    return ", ".join(parts) if parts else "none (no state repeats)"


def stability_word(mu_max: float, stable: bool, neutral: bool) -> str:
    if stable:
        return f"stable (largest |mu| {mu_max:.6g})"
    if neutral:
        return f"neutral (largest |mu| {mu_max:.6g}, 1 to the monodromy's accuracy)"
    return f"unstable (largest |mu| {mu_max:.6g})"


def orbit_text(orbit, model=None) -> str:
    closure = orbit.closure
    how = f"{closure.angle} advances by {closure.advance}" if closure.angle else \
        f"period {closure.period}"
    lines = [f"PERIODIC STEADY STATE OF {_title(model)}".rstrip(),
             f"{how}: period {orbit.period:.9g} s, "
             f"{len(orbit.events)} switches a period",
             f"Newton: {len(orbit.residuals) - 1} steps, largest residual "
             + " -> ".join(f"{r:.2E}" for r in orbit.residuals)
             + " (of each state's size)",
             f"state at the start (TIME = {orbit.t0:.9g}):",
             "  " + ", ".join(f"{n} = {orbit.value(n):.9g}" for n in orbit.names)]
    if orbit.free:
        lines.append(f"left out of the periodicity (nothing depends on them): "
                     f"{', '.join(orbit.free)}")
    lines += ["", f"{'OVER ONE PERIOD':<16}{'MIN':>16}{'MAX':>16}{'MEAN':>16}{'HALF P-P':>16}"]
    for name, s in orbit.measures.items():
        lines.append(f"{name:<16}{s.minimum:16.8E}{s.maximum:16.8E}{s.mean:16.8E}"
                     f"{s.half_pp:16.8E}")
    lines += ["", f"Floquet multipliers: {_multipliers(orbit.multipliers)}"]
    if orbit.symmetries is not None and orbit.symmetries.shape[1]:
        for v in orbit.symmetries.T:
            moved = ", ".join(f"{n} {c:.4g}" for n, c in zip(orbit.cyclic, v, strict=True)
                              if abs(c) > 1e-9)
            lines.append(f"  and a trivial 1: the field does not change along ({moved}), "
                         "so every orbit shifted that way is one too")
    lines.append(stability_word(orbit.mu_max, orbit.stable, orbit.neutral))
    return "\n".join(lines) + "\n"


def orbit_csv(orbit) -> tuple[list[str], Iterator[list]]:
    header = ["PERIOD"]
    row: list = [orbit.period]
    for name, s in orbit.measures.items():
        header += [f"MIN_{name}", f"MAX_{name}", f"MEAN_{name}", f"HALF_PP_{name}"]
        row += [s.minimum, s.maximum, s.mean, s.half_pp]
    header += ["STABLE", "MU_MAX"]
    row += [int(orbit.stable), orbit.mu_max]
    return header, iter([row])


@literal_text
def plot_orbit(orbit, path: str, model=None, formats: Sequence[str] = ()) -> list[str]:
    """The measured variables over one period; saved as `path` (or in each of
    `formats` beside it): the paths written."""
    from matplotlib.figure import Figure

    times, values = orbit.samples
    names = list(orbit.measures)
    fig = Figure(figsize=(8, 2.2 + 1.8 * len(names)))
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    order = np.argsort(times, kind="stable")
    for ax, name, row in zip(axes, names, values, strict=True):
        unit = units(model, None, name)[1]
        ax.plot(times[order] - orbit.t0, row[order], color="tab:blue", linewidth=1.3)
        ax.set_ylabel(name + (f" [{unit}]" if unit else ""))
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel(f"TIME - {orbit.t0:.6g} [s]")
    word = "stable" if orbit.stable else ("neutral" if orbit.neutral else "unstable")
    axes[0].set_title(f"{W.shorten(_title(model), 90)}\none period: T = {orbit.period:.6g} s,"
                      f" {word} (largest |mu| {orbit.mu_max:.4g})", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, formats)


# ----------------------------------------------------------------- response

def response_text(resp, model=None) -> str:
    m0 = resp.measures[0]
    closure = resp.closure
    how = f"{closure.angle} advances by {closure.advance}" if closure.angle else \
        f"period {closure.period}"
    lines = [f"RESPONSE OF {_title(model)}".rstrip(),
             f"half peak-to-peak of {m0} against {resp.name}, {how}; "
             f"{sum(1 for p in resp.points if not p.kind or p.kind == 'end')} orbits",
             "", f"{resp.name:>14}{'PERIOD':>14}" + "".join(
                 f"{'MIN_' + m:>14}{'MAX_' + m:>14}{'HALF_PP_' + m:>14}" for m in resp.measures)
             + f"{'STABLE':>8}{'MU_MAX':>12}"]
    for p in resp.points:
        cells = "".join(f"{p.measures[m].minimum:14.6E}{p.measures[m].maximum:14.6E}"
                        f"{p.measures[m].half_pp:14.6E}" for m in resp.measures)
        mark = f"  {p.kind}" if p.kind and p.kind != "end" else ""
        lines.append(f"{p.value:14.7g}{p.period:14.7g}{cells}"
                     f"{'yes' if p.stable else 'no':>8}{p.mu_max:12.6g}{mark}")
    lines.append("")
    for p in resp.folds:
        lines.append(f"fold at {resp.name} = {p.value:.7g} ({'HALF_PP_' + m0} = "
                     f"{p.measures[m0].half_pp:.6g})")
    lines += resp.notes
    if not resp.complete:
        lines.append(f"the curve ends at {resp.name} = {resp.points[-1].value:.7g}, short of "
                     "the range: partial")
    return "\n".join(lines) + "\n"


def response_csv(resp) -> tuple[list[str], Iterator[list]]:
    header = [resp.name, "PERIOD"]
    for m in resp.measures:
        header += [f"MIN_{m}", f"MAX_{m}", f"HALF_PP_{m}"]
    header += ["STABLE", "MU_MAX", "KIND"]

    def rows():
        for p in resp.points:
            row: list = [p.value, p.period]
            for m in resp.measures:
                s = p.measures[m]
                row += [s.minimum, s.maximum, s.half_pp]
            yield row + [int(p.stable), p.mu_max, p.kind]
    return header, rows()


def _runs(points: Sequence, measure: str) -> list[tuple[bool, list, list]]:
    """The curve in pieces of one stability, each piece joined to the next."""
    pieces: list[tuple[bool, list, list]] = []
    for p in points:
        if p.kind == "fold":
            continue
        x, y = p.value, p.measures[measure].half_pp
        if pieces and pieces[-1][0] == p.stable:
            pieces[-1][1].append(x)
            pieces[-1][2].append(y)
            continue
        if pieces:  # start where the last piece ended
            pieces.append((p.stable, [pieces[-1][1][-1], x], [pieces[-1][2][-1], y]))
        else:
            pieces.append((p.stable, [x], [y]))
    return pieces


@literal_text
def plot_response(resp, path: str, model=None, reference=None,
                  formats: Sequence[str] = ()) -> list[str]:
    """Half peak-to-peak of the first measure against the value: stable solid,
    unstable dashed, folds marked. `reference`: extra curves to compare, each
    (x, y, label) or (x, y, label, matplotlib format such as "v" or "k:"). Saved
    as `path` (or in each of `formats` beside it): the paths written."""
    from matplotlib.figure import Figure

    m0 = resp.measures[0]
    fig = Figure(figsize=(8, 4.8))
    ax = fig.subplots()
    seen = set()
    for stable, xs, ys in _runs(resp.points, m0):
        label = "stable" if stable else "unstable"
        ax.plot(xs, ys, color="tab:blue" if stable else "tab:red",
                linestyle="-" if stable else "--", linewidth=1.5,
                label=None if label in seen else label)
        seen.add(label)
    folds = resp.folds
    if folds:
        ax.plot([p.value for p in folds], [p.measures[m0].half_pp for p in folds], "ko",
                markersize=5, label="fold")
        for p in folds:
            ax.annotate(f"{p.value:.5g}", (p.value, p.measures[m0].half_pp),
                        textcoords="offset points", xytext=(6, -10), fontsize=8)
    for x, y, label, *fmt in reference or ():
        ax.plot(x, y, *(fmt or ["."]), markersize=3, label=label,
                **({} if fmt else {"color": "0.55"}))
    x_unit, y_unit = units(model, resp.name, m0)
    ax.set_xlabel(resp.name + (f" [{x_unit}]" if x_unit else ""))
    ax.set_ylabel(f"half peak-to-peak of {m0}" + (f" [{y_unit}]" if y_unit else ""))
    ax.set_title(W.shorten(f"{_title(model)}: response in {resp.name}", 90), fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path, formats)


def figure_stem(out_dir: str, stem: str, what: str) -> str:
    """Where an analysis's figure goes, without its extension (one per --format)."""
    return os.path.join(out_dir, f"{stem}_{what}")
