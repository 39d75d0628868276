"""Sensitivities for a reader: local coefficients over time
(`analysis.sensitivity.Local`) and global indices (`batch.indices.Indices`) as
printouts, CSV rows and figures."""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence

import numpy as np

from ..analysis.sensitivity import Local
from . import words as W
from .analysis import _title
from .plot import save_figure

FAILED_LISTED = 20


def _num(x: float, width: int = 14) -> str:
    return f"{x:{width}.6E}" if math.isfinite(x) else f"{'-':>{width}}"


def _fix(x: float, width: int = 10) -> str:
    return f"{x:{width}.4f}" if math.isfinite(x) else f"{'-':>{width}}"


# ------------------------------------------------------------------- local

def local_text(loc, model=None) -> str:
    lines = [f"LOCAL SENSITIVITIES OF {_title(model)}".rstrip(),
             "S = (P / Y) dY/dP: the percent change of Y per percent change of P, at "
             + ", ".join(f"{n} = {v:.6g}" for n, v in loc.values.items()),
             f"from the {loc.how}", "",
             "LARGEST |P dY/dP| OVER THE RUN, OVER THE LARGEST |Y| (the ranking: S itself "
             "grows without bound near a zero of Y)",
             f"{'':<12}" + "".join(f"{n:>14}" for n in loc.names)]
    big = loc.largest()
    for i, v in enumerate(loc.variables):
        lines.append(f"{v:<12}" + "".join(_num(float(x)) for x in big[i]))
    norm = loc.normalised
    index = np.flatnonzero(loc.prdel)
    for i, v in enumerate(loc.variables):
        lines += ["", f"{v}: S AT THE PRDEL INSTANTS",
                  f"{'TIME':>14}{v:>14}" + "".join(f"{'S ' + n:>14}" for n in loc.names)]
        for k in index:
            lines.append(_num(float(loc.times[k])) + _num(float(loc.y[k, i]))
                         + "".join(_num(float(x)) for x in norm[k, i]))
    return "\n".join(lines) + "\n"


def local_csv(loc) -> tuple[list[str], Iterator[list]]:
    """TIME, then per variable its value, S_<VAR>_<P> (normalised) and D_<VAR>_<P>
    (dY/dP) for each data value, on the output grid."""
    header = ["TIME"]
    for v in loc.variables:
        header += [v, *(f"S_{v}_{n}" for n in loc.names), *(f"D_{v}_{n}" for n in loc.names)]
    norm = loc.normalised

    def rows():
        for k, t in enumerate(loc.times.tolist()):
            row: list = [t]
            for i in range(len(loc.variables)):
                row += [float(loc.y[k, i]), *map(float, norm[k, i]), *map(float, loc.raw[k, i])]
            yield row
    return header, rows()


def plot_local(loc, stem: str, model=None, formats: Sequence[str] = ()) -> list[str]:
    """One figure per variable: S of each data value against TIME."""
    from matplotlib.figure import Figure

    out = []
    norm = loc.normalised
    for i, v in enumerate(loc.variables):
        fig = Figure(figsize=(8, 4.2))
        ax = fig.subplots()
        for j, n in enumerate(loc.names):
            ax.plot(loc.times, norm[:, i, j], linewidth=1.3, label=n)
        ax.axhline(0.0, color="0.5", linewidth=0.8)
        ax.set_xlabel("TIME")
        ax.set_ylabel(f"(P/{v}) d{v}/dP")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(f"{W.shorten(_title(model), 90)}\nnormalised sensitivity of {v}",
                     fontsize=10)
        fig.tight_layout()
        out += save_figure(fig, f"{stem}_{v}", formats or ("png",))
    return out


# ------------------------------------------------------------------ global

def indices_text(ind, model=None) -> str:
    word = {"sobol": "SOBOL INDICES", "morris": "MORRIS ELEMENTARY EFFECTS"}[ind.method]
    how = (f"N = {ind.base} rows of a scrambled Sobol sequence, {ind.runs} runs"
           if ind.method == "sobol" else f"r = {ind.base} trajectories, {ind.runs} runs")
    lines = [f"{word} OF {_title(model)}".rstrip(),
             f"{how} (seed {ind.seed}); {len(ind.failed)} failed",
             "drawn: " + "; ".join(f"{n} {d.text()}" for n, d in ind.dists.items())]
    lines += [f"note: {n}" for n in ind.notes]
    if ind.interrupted or ind.timed_out:
        lines.append("the study stopped early: the indices are of the runs done")
    for m, measure in enumerate(ind.measures):
        lines += ["", f"OUTPUT {measure.text}"]
        if ind.method == "sobol":
            lines.append(f"{'':<12}{'FIRST':>10}{'95 % INTERVAL':>22}{'TOTAL':>10}"
                         f"{'95 % INTERVAL':>22}")
            order = np.argsort(-np.nan_to_num(ind.total[m], nan=-1.0), kind="stable")
            for j in order:
                fc = ind.first_ci[m, j] if ind.first_ci is not None else (math.nan,) * 2
                tc = ind.total_ci[m, j] if ind.total_ci is not None else (math.nan,) * 2
                lines.append(f"  {ind.names[j]:<10}{_fix(ind.first[m, j])}"
                             f"{_fix(fc[0], 11)}{_fix(fc[1], 11)}{_fix(ind.total[m, j])}"
                             f"{_fix(tc[0], 11)}{_fix(tc[1], 11)}")
            lines.append(f"  variance of the output {ind.variance[m]:.6g}; first-order "
                         f"sum {np.nansum(ind.first[m]):.4f}")
        else:
            lines.append(f"{'':<12}{'MU*':>14}{'MU':>14}{'SIGMA':>14}")
            order = np.argsort(-np.nan_to_num(ind.mu_star[m], nan=-1.0), kind="stable")
            for j in order:
                lines.append(f"  {ind.names[j]:<10}{_num(ind.mu_star[m, j])}"
                             f"{_num(ind.mu[m, j])}{_num(ind.sigma[m, j])}")
            lines.append("  (MU*: the mean |change| of the output per unit change of a value's "
                         "probability, for a uniform value per its whole range; SIGMA: "
                         "interactions or nonlinearity)")
    if ind.failed:
        lines += ["", f"FAILED RUNS ({len(ind.failed)})"]
        for k in ind.failed[:FAILED_LISTED]:
            values = ", ".join(f"{n} = {v[k]:.6g}" for n, v in ind.samples.items())
            text = (ind.messages.get(k) or "failed").strip().splitlines()[0]
            lines.append(f"  run {k + 1}: {values}: {text}")
    return "\n".join(lines) + "\n"


def indices_csv(ind) -> tuple[list[str], Iterator[list]]:
    """A row per measure and drawn value: MEASURE, NAME, then S1, S1_LO, S1_HI, ST,
    ST_LO, ST_HI (Sobol) or MU_STAR, MU, SIGMA (Morris)."""
    if ind.method == "sobol":
        header = ["MEASURE", "NAME", "S1", "S1_LO", "S1_HI", "ST", "ST_LO", "ST_HI"]

        def rows():
            for m, measure in enumerate(ind.measures):
                for j, n in enumerate(ind.names):
                    fc = ind.first_ci[m, j] if ind.first_ci is not None else (math.nan,) * 2
                    tc = ind.total_ci[m, j] if ind.total_ci is not None else (math.nan,) * 2
                    yield [measure.text, n, float(ind.first[m, j]), *map(float, fc),
                           float(ind.total[m, j]), *map(float, tc)]
    else:
        header = ["MEASURE", "NAME", "MU_STAR", "MU", "SIGMA"]

        def rows():
            for m, measure in enumerate(ind.measures):
                for j, n in enumerate(ind.names):
                    yield [measure.text, n, float(ind.mu_star[m, j]), float(ind.mu[m, j]),
                           float(ind.sigma[m, j])]
    return header, rows()


def plot_indices(ind, stem: str, model=None, formats: Sequence[str] = ()) -> list[str]:
    """One bar chart of the indices of every measure."""
    from matplotlib.figure import Figure

    count = len(ind.measures)
    fig = Figure(figsize=(8, 1.6 + 2.2 * count))
    axes = fig.subplots(count, 1, squeeze=False)[:, 0]
    x = np.arange(len(ind.names))
    for m, (ax, measure) in enumerate(zip(axes, ind.measures, strict=True)):
        if ind.method == "sobol":
            ax.bar(x - 0.2, ind.first[m], 0.4, label="first order", color="tab:blue")
            ax.bar(x + 0.2, ind.total[m], 0.4, label="total", color="tab:orange")
            if ind.total_ci is not None:
                for j in range(len(x)):
                    ax.plot([x[j] + 0.2] * 2, ind.total_ci[m, j], color="k", linewidth=1)
                    ax.plot([x[j] - 0.2] * 2, ind.first_ci[m, j], color="k", linewidth=1)
            ax.set_ylabel("index")
        else:
            ax.bar(x - 0.2, ind.mu_star[m], 0.4, label="mu*", color="tab:blue")
            ax.bar(x + 0.2, ind.sigma[m], 0.4, label="sigma", color="tab:orange")
            ax.set_ylabel("effect")
        ax.set_xticks(x, ind.names)
        ax.set_title(measure.text, fontsize=9)
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize=8)
    word = "Sobol indices (95 % intervals)" if ind.method == "sobol" else \
        "Morris elementary effects"
    fig.suptitle(f"{W.shorten(_title(model), 90)}\n{word}", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, stem, formats or ("png",))


def sensitivity_csv(result) -> tuple[list[str], Iterator[list]]:
    """`local_csv` or `indices_csv`, as the result is."""
    return (local_csv if isinstance(result, Local) else indices_csv)(result)


def plot_sensitivity(result, stem: str, model=None, formats: Sequence[str] = ()) -> list[str]:
    """`plot_local` or `plot_indices`, as the result is."""
    draw = plot_local if isinstance(result, Local) else plot_indices
    return draw(result, stem, model, formats)
