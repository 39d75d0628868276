"""Runs -> figures: one per OUTPUT statement, runs overlaid, LABEL as title.

matplotlib is imported here only, and only when a plot is asked for.
"""

from __future__ import annotations

import io
import os

from .printout import atomic_write, report_names
from .result import Run


def figure_specs(run: Run) -> list[tuple[list[str], str | None]]:
    specs = [(list(r.names), r.label) for r in run.reports if r.kind == "OUTPUT"]
    if not specs:
        names = report_names(run, "PRINT") or [n for n in run.values if "#" not in n][:6]
        specs = [(names, None)]
    return specs


def plot_runs(runs: list[Run], out_dir: str, stem: str, show: bool = False) -> list[str]:
    """Draw and save one PNG per OUTPUT statement; return the paths written."""
    import matplotlib

    if not show:
        matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    paths = []
    specs = figure_specs(runs[0])
    for k, (names, label) in enumerate(specs, start=1):
        fig, ax = plt.subplots(figsize=(8, 4.8))
        for run in runs:
            for name in names:
                if name == "TIME" or name not in run:
                    continue
                tag = name if len(runs) == 1 else f"{name} ({run.label})"
                ax.plot(run.t, run[name], label=tag, linewidth=1.2)
            for e in run.events[:200]:
                if e.kind == "breakpoint" and len(runs) == 1:
                    ax.axvline(e.time, color="0.8", linewidth=0.6, zorder=0)
        title = label or (runs[0].titles[0] if runs[0].titles else ", ".join(names))
        ax.set_title(title)
        ax.set_xlabel("TIME")
        ax.set_ylabel(", ".join(names))
        ax.grid(True, alpha=0.3)
        if len(names) > 1 or len(runs) > 1:
            ax.legend(fontsize=8)
        failed = [r for r in runs if not r.ok]
        if failed:
            ax.text(0.01, 0.01, "partial: " + failed[0].message, transform=ax.transAxes,
                    fontsize=7, color="red")
        fig.tight_layout()
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110)
        path = os.path.join(out_dir, f"{stem}_{k}.png" if len(specs) > 1 else f"{stem}.png")
        atomic_write(path, buf.getvalue())
        paths.append(path)
        if not show:
            plt.close(fig)
    if show:
        plt.show()
    return paths


def display_available() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
