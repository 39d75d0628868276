"""A Monte Carlo for a reader (`amilpy.batch.montecarlo` computes it): the
printout, the bands as CSV, every run's drawn and final values as CSV, and
figures of the bands."""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence

import numpy as np

from . import words as W
from .analysis import _title
from .plot import save_figure

FAILED_LISTED = 20  # failed runs listed in the printout (all of them in --samples)


def _q(q: float) -> str:
    return f"P{q:.10g}"


def _num(x: float, width: int = 14) -> str:
    return f"{x:{width}.6E}" if math.isfinite(x) else f"{'-':>{width}}"


def montecarlo_text(mc, model=None) -> str:
    kept = int(np.sum(mc.kept))
    lines = [f"MONTE CARLO OF {_title(model)}".rstrip(),
             f"{mc.runs} runs drawn with seed {mc.seed}; {mc.done} run, {kept} kept, "
             f"{len(mc.failed)} failed" +
             ("; interrupted: the runs done are kept" if mc.interrupted else "") +
             ("; the time limit ran out: the runs done are kept" if mc.timed_out else ""),
             *([mc.how] if mc.how else []),
             "", "DRAWN VALUES" + "".join(f"{h:>14}" for h in ("MEAN", "SD", "MIN", "MAX")),
             ]
    for name, values in mc.samples.items():
        lines.append(f"  {name:<10}" + _num(float(np.mean(values)))
                     + _num(float(np.std(values, ddof=1)) if len(values) > 1 else math.nan)
                     + _num(float(np.min(values))) + _num(float(np.max(values)))
                     + f"  {mc.dists[name].text()}")
    for (a, b), r in mc.correlation.items():
        if len(mc.samples[a]) > 2:
            from scipy.stats import spearmanr

            got = float(spearmanr(mc.samples[a], mc.samples[b])[0])
            lines.append(f"  {a} and {b}: correlation {r:g} of the normal scores; rank "
                         f"correlation {got:.4f} drawn, {6 / math.pi * math.asin(r / 2):.4f} "
                         "expected")
    head = "".join(f"{_q(q):>14}" for q in mc.quantiles)
    lines += ["", f"FINAL VALUES{'':<3}{'MEAN':>14}{head}"]
    fq = mc.final_quantiles()
    with np.errstate(all="ignore"):
        fmean = np.nanmean(mc.final[mc.kept], axis=0) if kept else \
            np.full(len(mc.variables), math.nan)
    for j, name in enumerate(mc.variables):
        lines.append(f"  {name:<13}{_num(float(fmean[j]))}"
                     + "".join(_num(float(v)) for v in fq[:, j]))
    if mc.terminal_names:
        tq = mc.terminal_quantiles()
        lines += ["", f"TERMINAL VALUES{'':<14}{head}"]
        for j, name in enumerate(mc.terminal_names):
            lines.append(f"  {name:<27}" + "".join(_num(float(v)) for v in tq[:, j]))
    index = np.flatnonzero(mc.prdel) if len(mc.times) else np.empty(0, int)
    for j, name in enumerate(mc.variables):
        lines += ["", f"{name}: QUANTILES OVER THE RUNS AT THE PRDEL INSTANTS",
                  f"{'TIME':>14}{'MEAN':>14}{head}{'RUNS':>8}"]
        for i in index:
            lines.append(_num(float(mc.times[i])) + _num(float(mc.mean[i, j]))
                         + "".join(_num(float(v)) for v in mc.bands[:, i, j])
                         + f"{int(mc.counts[i]):8d}")
    if mc.failed:
        lines += ["", f"FAILED RUNS ({len(mc.failed)}, left out of the quantiles"
                      + (f"; the first {FAILED_LISTED} here, all in --samples"
                         if len(mc.failed) > FAILED_LISTED else "") + ")"]
        for k in mc.failed[:FAILED_LISTED]:
            values = ", ".join(f"{n} = {v:.6g}" for n, v in mc.values_of(k).items())
            lines.append(f"  run {k + 1}: {values}: {_first_line(mc.messages[k])}")
    return "\n".join(lines) + "\n"


def _first_line(text: str) -> str:
    return (text or "failed").strip().splitlines()[0] if text else "failed"


def bands_csv(mc) -> tuple[list[str], Iterator[list]]:
    """TIME, then per variable its MEAN and each quantile (NAME_MEAN, NAME_P5, ...),
    then RUNS (how many runs each row's quantiles are of), on the output grid."""
    header = ["TIME"]
    for name in mc.variables:
        header += [f"{name}_MEAN", *(f"{name}_{_q(q)}" for q in mc.quantiles)]
    header.append("RUNS")

    def rows():
        for i, t in enumerate(mc.times.tolist()):
            row: list = [t]
            for j in range(len(mc.variables)):
                row += [float(mc.mean[i, j]), *(float(v) for v in mc.bands[:, i, j])]
            row.append(int(mc.counts[i]))
            yield row
    return header, rows()


def samples_csv(mc) -> tuple[list[str], Iterator[list]]:
    """One row per run: RUN, STATUS, the drawn values, the final values
    (FINAL_<NAME>), the TERMINAL values, MESSAGE (a failed run's)."""
    header = ["RUN", "STATUS", *mc.samples, *(f"FINAL_{n}" for n in mc.variables),
              *mc.terminal_names, "MESSAGE"]

    def rows():
        for k in range(mc.runs):
            yield [k + 1, mc.status[k] or "not run",
                   *(float(v[k]) for v in mc.samples.values()),
                   *(float(v) for v in mc.final[k]), *(float(v) for v in mc.terminal[k]),
                   _first_line(mc.messages[k]) if mc.status[k] == "failed" else ""]
    return header, rows()


def plot_bands(mc, stem: str, model=None, formats: Sequence[str] = ()) -> list[str]:
    """One figure per OUTPUT statement (else per variable): the median (or middle
    quantile) line, the outer quantiles shaded, an inner pair shaded darker."""
    groups = _figure_groups(mc, model)
    out = []
    notes = W.name_notes(model.ir) if model is not None else {}
    q = list(mc.quantiles)
    mid = q.index(50.0) if 50.0 in q else len(q) // 2
    for k, (names, label) in enumerate(groups, 1):
        from matplotlib.figure import Figure

        fig = Figure(figsize=(8, 2.4 + 2.0 * len(names)))
        axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
        for ax, name in zip(axes, names, strict=True):
            band = mc.band(name)
            color = "tab:blue"
            if len(q) >= 2:
                ax.fill_between(mc.times, band[0], band[-1], color=color, alpha=0.18,
                                linewidth=0, label=f"{_q(q[0])}-{_q(q[-1])}")
            if len(q) >= 4:
                ax.fill_between(mc.times, band[1], band[-2], color=color, alpha=0.3,
                                linewidth=0, label=f"{_q(q[1])}-{_q(q[-2])}")
            ax.plot(mc.times, band[mid], color=color, linewidth=1.5, label=_q(q[mid]))
            unit = W.unit_of([name], label, notes)
            ax.set_ylabel(name + (f" [{unit}]" if unit else ""))
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8, loc="best")
        axes[-1].set_xlabel("TIME")
        axes[0].set_title(f"{W.shorten(_title(model), 90)}\nMonte Carlo: {int(np.sum(mc.kept))}"
                          f" runs (seed {mc.seed}), quantiles over the runs", fontsize=10)
        fig.tight_layout()
        out += save_figure(fig, f"{stem}_{k}", formats or ("png",))
    return out


def _figure_groups(mc, model) -> list[tuple[list[str], str | None]]:
    """The OUTPUT statements' variables among those drawn in bands (each with its
    LABEL), else one figure of every variable."""
    groups = []
    if model is not None:
        for r in model.ir.runs[0].reports:
            if r.kind == "OUTPUT":
                names = [n for n in r.names if n in mc.variables]
                if names:
                    groups.append((names, r.label))
    return groups or [(list(mc.variables), None)]
