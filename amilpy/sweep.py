"""Parameter sweeps: one run per value, optionally each continuing from the last.

With `carry_state` a run starts from the previous run's final state (states,
memory, branches) and TIME goes on, which is how an amplitude-frequency
characteristic with jumps is measured: sweeping up and then down, the system
stays on the branch it is on until that branch ends at a fold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .diagnostics import AmilError
from .result import Run


@dataclass(frozen=True)
class SweepPoint:
    value: float
    direction: str  # "up" or "down"
    minimum: float
    maximum: float
    status: str
    t_start: float
    t_end: float

    @property
    def amplitude(self) -> float:
        """Half the peak-to-peak of the measured variable after the settling time."""
        return 0.5 * (self.maximum - self.minimum)


@dataclass
class Sweep:
    name: str
    measure: str
    settle: float
    points: list[SweepPoint] = field(default_factory=list)
    runs: list[Run] = field(default_factory=list)

    def branch(self, direction: str) -> tuple[np.ndarray, np.ndarray]:
        pts = [p for p in self.points if p.direction == direction]
        return (np.array([p.value for p in pts]), np.array([p.amplitude for p in pts]))

    def jumps(self) -> dict[str, tuple[float, float]]:
        """For each direction, the pair of neighbouring values with the largest
        change of amplitude (up: largest rise, down: largest fall)."""
        out = {}
        for direction, pick in (("up", np.argmax), ("down", np.argmin)):
            v, a = self.branch(direction)
            if len(v) >= 2:
                k = int(pick(np.diff(a)))
                out[direction] = (float(v[k]), float(v[k + 1]))
        return out

    def csv_text(self) -> str:
        lines = [f"DIRECTION,{self.name},MIN_{self.measure},MAX_{self.measure},"
                 f"HALF_PP_{self.measure},STATUS,TIME_START,TIME_END"]
        for p in self.points:
            lines.append(f"{p.direction},{p.value!r},{p.minimum!r},{p.maximum!r},"
                         f"{p.amplitude!r},{p.status},{p.t_start!r},{p.t_end!r}")
        return "\n".join(lines) + "\n"

    def format(self) -> str:
        head = (f"{'':6}{self.name:>14}{'MIN ' + self.measure:>16}{'MAX ' + self.measure:>16}"
                f"{'HALF P-P':>16}")
        rows = [f"SWEEP OF {self.name}, {self.measure} MEASURED AFTER {self.settle:g} S", head]
        for p in self.points:
            rows.append(f"{p.direction:6}{p.value:14.6g}{p.minimum:16.6E}{p.maximum:16.6E}"
                        f"{p.amplitude:16.6E}" + ("" if p.status != "failed" else "  FAILED"))
        return "\n".join(rows) + "\n"


def parse_range(text: str) -> tuple[str, list[float]]:
    """NAME=START:STOP:STEP -> (NAME, values), STOP included."""
    try:
        name, spec = text.split("=", 1)
        start, stop, step = (float(x) for x in spec.split(":"))
    except ValueError:
        raise AmilError(f"a sweep is NAME=START:STOP:STEP, got {text!r}") from None
    if step == 0 or (stop - start) / step < 0:
        raise AmilError(f"the step {step:g} does not lead from {start:g} to {stop:g}")
    n = int(math.floor((stop - start) / step + 1e-9))
    if n > 100_000:
        raise AmilError(f"the sweep has {n + 1} points (limit 100000)")
    values = [round(start + k * step, 12) for k in range(n + 1)]
    return name.strip().upper(), values


def sweep(model, name: str, values: list[float], *, both_ways: bool = False,
          carry_state: bool = False, settle: float = 0.0, measure: str | None = None,
          method: str | None = None, rtol: float | None = None, atol: float | None = None,
          fintim: float | None = None, keep_runs: bool = False, progress=None,
          **params: float) -> Sweep:
    """Run `model` once per value of data value `name` and measure `measure`."""
    from .runner import Options, simulate

    name = name.upper()
    if name not in model.ir.data_names:
        raise AmilError(f"{name} is not a PARAM/CONST/INCON value of this model")
    variables = model.ir.variables
    if measure is None:
        reports = model.ir.runs[0].reports
        named = [n for r in reports if r.kind in ("OUTPUT", "PRINT") for n in r.names]
        measure = named[0] if named else variables[0]
    measure = measure.upper()
    if measure not in variables:
        raise AmilError(f"{measure} is not a variable of the model")
    sequence = [(v, "up") for v in values]
    if both_ways:
        sequence += [(v, "down") for v in reversed(values[:-1])]
    result = Sweep(name, measure, settle)
    start = None
    for i, (value, direction) in enumerate(sequence):
        spec = model._specs({**params, name: value})[0]
        opts = Options(method=method, rtol=rtol, atol=atol,
                       start=start if carry_state else None, fintim=fintim)
        run = simulate(model.ir, spec, opts)
        t0 = float(run.times[0])
        keep = run.times >= t0 + settle
        v = run.values[measure][keep]
        lo, hi = (float(np.min(v)), float(np.max(v))) if v.size else (math.nan, math.nan)
        result.points.append(SweepPoint(value, direction, lo, hi, str(run.status), t0,
                                        float(run.t_end)))
        if keep_runs:
            result.runs.append(run)
        if progress is not None:
            progress(i + 1, len(sequence), value)
        if not run.ok:
            break  # what follows would start from a failed state
        start = run.final_state
    return result


def plot_sweep(result: Sweep, path: str, title: str | None = None) -> str:
    import io

    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    from .printout import atomic_write

    fig, ax = plt.subplots(figsize=(8, 4.8))
    for direction, colour, marker in (("up", "tab:blue", "^"), ("down", "tab:red", "v")):
        v, a = result.branch(direction)
        if len(v):
            ax.plot(v, a, color=colour, marker=marker, markersize=4, linewidth=1.2,
                    label=f"sweep {direction}")
    ax.set_xlabel(result.name)
    ax.set_ylabel(f"half peak-to-peak of {result.measure}")
    ax.set_title(title or f"{result.measure} against {result.name}")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    atomic_write(path, buf.getvalue())
    return path
