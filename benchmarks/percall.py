"""Per-call costs: one right-hand-side evaluation and one solver step, amilpy vs hand-written.

    OPENBLAS_NUM_THREADS=1 python benchmarks/percall.py [--models ...] [--number N]

For each case:

* ``rhs raw``: amilpy's generated ``rhs(t, ylist, modes, z)`` (``run.prepare(...).code.rhs``)
  against the hand-written ``f(t, ylist)``, both on Python floats;
* ``rhs as solver sees it``: the function a stepper calls with a NumPy array: amilpy's
  ``run.Flow.field(state)`` (``y.tolist()`` + try/except, as the run loop builds it) against
  ``lambda t, y: f(t, y.tolist())`` and against ``f(t, y)`` on the array itself (NumPy
  scalars: what a naive hand-written function pays);
* ``step``: one ``step()`` of SciPy's RK45 and LSODA classes driving each function
  (amilpy's own ``steppers.make_stepper`` for amilpy), median over a run of steps;
* ``per step of a run``: wall time / steps and / RHS evaluations of a whole amilpy run
  (AUTO, RKS, LSODA at rtol 1e-6) and of hand-written ``odeint`` / ``solve_ivp`` runs at
  the same tolerances: what the runner adds between steps.

Writes ``percall.csv`` and ``percall.md`` in ``--out`` (default ``benchmarks/results``).
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import statistics
import sys
import time
import timeit

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import ROOT, all_cases  # noqa: E402

SHIPPED = ["ex4_elastic", "ex4_clutch", "ex4_torque_meter", "hoist_backlash",
           "crank_slider_startup", "machine_unit"]


def _per_call(fn, number: int) -> float:
    """Best of 5 of the mean time per call [s]."""
    return min(timeit.repeat(fn, number=number, repeat=5)) / number


def _sample_state(case):
    """A state in the middle of the run (from the reference), listing names -> value."""
    g, ref = case.ref()
    k = len(g) // 2
    return float(g[k]), {n: float(ref[n][k]) for n in case.states}


def _step_cost(make, n_steps: int) -> float:
    """Median time of one step() over the first n_steps steps of a fresh solver."""
    solver = make()
    times = []
    for _ in range(n_steps):
        t0 = time.perf_counter()
        solver.step()
        times.append(time.perf_counter() - t0)
        if getattr(solver, "status", "running") != "running":
            break
    return statistics.median(times)


def measure(case, number: int = 20000, n_steps: int = 300) -> dict:
    from scipy.integrate import LSODA, RK45, odeint, solve_ivp

    import amilpy
    from amilpy.run import Flow, State
    from amilpy.steppers import make_stepper

    model = amilpy.loads(case.text, case.name)
    flow = Flow(model.ir, model.ir.runs[0])
    c = flow.code
    t, named = _sample_state(case)
    ylist = [named[n] for n in c.state_names]
    yarr = np.array(ylist)
    modes = [1.0] * len(c.watched)
    z = list(c.z0)
    f_hand = case.segments()[-1][1]
    hl = [named[n] for n in case.states]
    ha = np.array(hl)

    def hand_wrapped(tt, y):
        return f_hand(tt, y.tolist())

    ami = flow.field(State(yarr, tuple(modes), tuple(z)), t)
    row = {"case": case.name, "states": len(ylist)}
    row["rhs_amilpy_raw_us"] = _per_call(lambda: c.rhs(t, ylist, modes, z), number) * 1e6
    row["rhs_hand_raw_us"] = _per_call(lambda: f_hand(t, hl), number) * 1e6
    row["rhs_amilpy_wrapped_us"] = _per_call(lambda: ami(t, yarr), number) * 1e6
    row["rhs_hand_tolist_us"] = _per_call(lambda: hand_wrapped(t, ha), number) * 1e6
    row["rhs_hand_ndarray_us"] = _per_call(lambda: f_hand(t, ha), number) * 1e6

    fac = case.atol_factor()
    rtol, atol = 1e-6, 1e-6 * fac
    span = case.fintim
    for name, cls in (("RK45", RK45), ("LSODA", LSODA)):
        row[f"step_{name}_amilpy_us"] = _step_cost(lambda cls=cls, name=name: make_stepper(
            name, ami, t, yarr, t + span, rtol=rtol, atol=atol, delt=case.outdel,
            max_step=case.outdel), n_steps) * 1e6
        row[f"step_{name}_hand_us"] = _step_cost(lambda cls=cls: cls(
            hand_wrapped, t, ha, t + span, rtol=rtol, atol=atol, max_step=case.outdel),
            n_steps) * 1e6

    # whole runs: seconds per step and per evaluation
    model.run()
    for method in ("AUTO", "RKS", "LSODA"):
        secs = []
        try:
            for _ in range(3):
                t0 = time.perf_counter()
                r = model.run(method=method, rtol=rtol, atol=atol)[0]
                secs.append(time.perf_counter() - t0)
        except Exception as exc:  # noqa: BLE001 - a failing route is reported, not fatal
            print(f"{case.name} {method}: {type(exc).__name__}: {exc}"[:160])
            row[f"run_{method}_ms"] = row[f"run_{method}_us_per_fev"] = math.nan
            row[f"run_{method}_nfev"] = row[f"run_{method}_nsteps"] = "error"
            continue
        s = statistics.median(secs)
        row[f"run_{method}_ms"] = s * 1e3
        row[f"run_{method}_nfev"] = r.stats["nfev"]
        row[f"run_{method}_nsteps"] = r.stats["nsteps"]
        row[f"run_{method}_us_per_fev"] = s / max(r.stats["nfev"], 1) * 1e6
    grid, _ = case.ref()
    f0 = case.segments()[0][1]  # first segment only: enough for a per-evaluation cost
    t_end0 = case.segments()[0][0]
    g0 = np.concatenate([[0.0], grid[(grid > 0) & (grid <= t_end0)]])

    def run_odeint():
        return odeint(lambda tt, y: f0(tt, y.tolist()), case.y0, g0, tfirst=True, rtol=rtol,
                      atol=atol, mxstep=10**7, full_output=True)[1]

    def run_ivp(method):
        return solve_ivp(lambda tt, y: f0(tt, y.tolist()), (0.0, g0[-1]), case.y0,
                         method=method, t_eval=g0, rtol=rtol, atol=atol)

    for label, fn, nfev_of in (("odeint", run_odeint, lambda i: int(i["nfe"][-1])),
                               ("ivp_LSODA", lambda: run_ivp("LSODA"), lambda s: s.nfev),
                               ("ivp_RK45", lambda: run_ivp("RK45"), lambda s: s.nfev)):
        secs = []
        for _ in range(3):
            t0 = time.perf_counter()
            res = fn()
            secs.append(time.perf_counter() - t0)
        s = statistics.median(secs)
        row[f"hand_{label}_ms"] = s * 1e3
        row[f"hand_{label}_nfev"] = nfev_of(res)
        row[f"hand_{label}_us_per_fev"] = s / max(nfev_of(res), 1) * 1e6
    return row


def markdown(rows) -> str:
    def g(x):
        return "" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.3g}"

    out = ["### One RHS evaluation [µs]", "",
           "| case | states | amilpy rhs (floats) | hand f (floats) | amilpy as stepper calls it "
           "(ndarray) | hand f(y.tolist()) | hand f(ndarray) |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['case']} | {r['states']} | {g(r['rhs_amilpy_raw_us'])} | "
                   f"{g(r['rhs_hand_raw_us'])} | {g(r['rhs_amilpy_wrapped_us'])} | "
                   f"{g(r['rhs_hand_tolist_us'])} | {g(r['rhs_hand_ndarray_us'])} |")
    out += ["", "### One solver step() [µs] (SciPy class, rtol 1e-6, max_step = OUTDEL)", "",
            "| case | RK45 amilpy | RK45 hand | LSODA amilpy | LSODA hand |",
            "|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['case']} | {g(r['step_RK45_amilpy_us'])} | {g(r['step_RK45_hand_us'])} "
                   f"| {g(r['step_LSODA_amilpy_us'])} | {g(r['step_LSODA_hand_us'])} |")
    out += ["", "### Whole runs at rtol 1e-6: wall time per RHS evaluation [µs] (nfev)", "",
            "| case | amilpy AUTO | amilpy RKS | amilpy LSODA | hand odeint | hand ivp LSODA "
            "| hand ivp RK45 |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        cells = [f"{g(r[f'run_{m}_us_per_fev'])} ({r[f'run_{m}_nfev']})"
                 for m in ("AUTO", "RKS", "LSODA")]
        cells += [f"{g(r[f'hand_{m}_us_per_fev'])} ({r[f'hand_{m}_nfev']})"
                  for m in ("odeint", "ivp_LSODA", "ivp_RK45")]
        out.append(f"| {r['case']} | " + " | ".join(cells) + " |")
    out += ["", "(hand-written runs: first TIME segment only for ex4_clutch / fsw_on_time.)"]
    return "\n".join(out) + "\n"


def main(models=None, number: int = 20000, n_steps: int = 300, out_dir: str | None = None):
    cases = all_cases()
    rows = []
    for name in models or SHIPPED:
        rows.append(measure(cases[name], number, n_steps))
        print(name, {k: round(v, 3) if isinstance(v, float) else v for k, v in rows[-1].items()},
              flush=True)
    out_dir = out_dir or os.path.join(ROOT, "benchmarks", "results")
    os.makedirs(out_dir, exist_ok=True)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(os.path.join(out_dir, "percall.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, keys)
        w.writeheader()
        w.writerows(rows)
    md = markdown(rows)
    with open(os.path.join(out_dir, "percall.md"), "w") as fh:
        fh.write(md)
    print(md)
    return rows


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="*")
    p.add_argument("--number", type=int, default=20000)
    p.add_argument("--out", default=None)
    a = p.parse_args()
    main(a.models, a.number, out_dir=a.out)
