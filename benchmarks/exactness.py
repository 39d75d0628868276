"""Exact by default (issue 21): the default route on the six shipped models, its time and
its error against the exact references, whatever the output grid; and what watching the
switching surfaces at every integrator step costs on each candidate way of doing it.

    OPENBLAS_NUM_THREADS=1 python benchmarks/exactness.py [--repeats 5] [--out DIR]
    python benchmarks/exactness.py --before /path/to/older/checkout --rtol 1e-10 ...
    python benchmarks/exactness.py --before ... --instructions   # (needs valgrind)
    python benchmarks/exactness.py --before ... --only-equal-error --out DIR

`--equal-error` (with `--before`): both trees over RELERR 1e-5 ... 1e-11, the time each
takes at equal error (read off each one's work-precision front), and their ratio; with
`--only-equal-error` that table alone, written to exactness_equal_error.md.

Table 1 (`default route`): METHOD AUTO at RELERR `--rtol` (default: the listing's
default, which is 1e-10 now), ABSERR = RELERR x `--atol-ratio` (1e-3, as the defaults):
CPU time of a run (`time.process_time`, the median of `--repeats`, the model compiled
before), evaluations, events, and the error of every state on the OUTDEL grid against
`cases.py`'s exact references (max |y - y_ref| / max |y_ref|); then the same model with
OUTDEL 20 times coarser: its events and its error on the grid rows it shares with the
reference. The script reads amilpy's public API only, so it measures older code too:
`--before PATH` (a checkout of it) adds its columns, at the same RELERR and at its own
defaults; each model's runs then take turns, one fresh process per tree and round, this
tree's and the older one's alternating (`--repeats` rounds, the median), so the
machine's drift falls on both alike.

Table 2 (`candidates`): ways to look at every switching surface after every step
(issue 21 point 1), on the six models' right-hand sides with the branches as they are at
t = 0 and no event handled, to FINTIM, rows on the OUTDEL grid: the cost floor of each
way, side by side, without the loop around it.

* `odeint` - Fortran/C LSODA through `scipy.integrate.odeint` over the output grid: no
  surface looked at between the rows (AUTO before this issue);
* `odeint+log` - the same call, every evaluation logged, the accepted step ends recovered
  from the log and the surfaces evaluated at all of them over NumPy columns (AUTO now);
* `lsoda 1-step` - the same C LSODA called for one step at a time
  (`scipy.integrate._odepack.lsoda`, itask 5), the surfaces after each step (the leanest
  Python loop around LSODA: what per-step checking costs at the least);
* `LSODA class` - SciPy's `LSODA` OdeSolver stepped by hand, the surfaces after each step
  (METHOD LSODA's stepper);
* `CVODE roots` - SUNDIALS CVODE (BDF) with its own root finding on the surfaces
  (`scikit-sundae`), when it is installed.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
import warnings

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from cases import all_cases, error_on_grid  # noqa: E402

SHIPPED = ["ex4_elastic", "ex4_clutch", "ex4_torque_meter", "hoist_backlash",
           "crank_slider_startup", "machine_unit"]


def _cpu(fn, repeats: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeats):
        t0 = time.process_time()
        out = fn()
        times.append(time.process_time() - t0)
    return statistics.median(times), out


def coarser(text: str, outdel: float, factor: float) -> str:
    """The listing with OUTDEL `factor` times coarser."""
    import re

    new, n = re.subn(r"OUTDEL\s*=\s*[0-9.Ee+-]+", f"OUTDEL = {outdel * factor!r}", text)
    assert n == 1, "one OUTDEL in the TIMER statement"
    return new


def measure(name: str, rtol, atol_ratio: float, repeats: int) -> dict:
    """One model on the default route, in this process's amilpy."""
    import amilpy

    case = all_cases()[name]
    kw = {} if rtol is None else {"rtol": rtol, "atol": rtol * atol_ratio}
    model = amilpy.loads(case.text, case.name)
    model.run(advice=False, **kw)
    seconds, runs = _cpu(lambda m=model, kw=kw: m.run(advice=False, **kw), repeats)
    r = runs[0]
    coarse = amilpy.loads(coarser(case.text, case.outdel, 20.0), case.name)
    rc = coarse.run(advice=False, **kw)[0]
    return {"model": name, "settings": r.settings, "ms": 1e3 * seconds,
            "nfev": r.stats.get("nfev"), "events": len(r.events),
            "error": error_on_grid(case, r.t, {n: r[n] for n in case.states}),
            "coarse events": len(rc.events), "coarse error": _coarse_error(case, rc)}


def _in_child(tree: str | None, name: str, rtol, atol_ratio: float) -> dict:
    """`measure` in a fresh process whose amilpy is the one in `tree` (None: this
    one), one timed run after a first one."""
    import json
    import subprocess

    # amilpy imported first, from `tree`: cases.py puts this tree on the path after
    code = ("import json, sys\n"
            + (f"sys.path.insert(0, {tree!r})\n" if tree else "")
            + "import amilpy\n"
            f"sys.path.insert(1, {HERE!r})\n"
            "import exactness\n"
            f"row = exactness.measure({name!r}, {rtol!r}, {atol_ratio!r}, 1)\n"
            "row['amilpy'] = amilpy.__file__\n"
            "print(json.dumps(row))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=tree or os.getcwd())
    return json.loads(out.stdout.strip().splitlines()[-1])


# A child that counts the instructions of `runs` runs of one model under callgrind:
# only those runs (the imports, the code generation and a first run are not counted),
# with Python's hashing fixed and the chunks' wall-clock limit lifted (under valgrind a
# chunk takes 50 times longer, and a tree that sizes its chunks by the clock would cut
# them shorter than it does when not counted)
_COUNTED = """
import os, subprocess, sys
sys.path.insert(0, {tree!r})
import amilpy
try:
    from amilpy.run import segment
    segment.CHUNK_SECONDS = 1e9
except ImportError:
    pass
sys.path.insert(1, {here!r})
from cases import all_cases
case = all_cases()[{name!r}]
kw = {kw!r}
model = amilpy.loads(case.text, case.name)
model.run(advice=False, **kw)
subprocess.run(["callgrind_control", "-i", "on", str(os.getpid())], capture_output=True)
for _ in range({runs}):
    model.run(advice=False, **kw)
subprocess.run(["callgrind_control", "-i", "off", str(os.getpid())], capture_output=True)
"""


def instructions(tree: str | None, name: str, rtol, atol_ratio: float, runs: int = 2
                 ) -> float:
    """Millions of instructions a run of `name` takes on the default route with the
    amilpy in `tree` (None: this one), counted by callgrind: the same count every
    time, whatever else the machine does, where CPU time on a shared 2-core machine
    varies by a third from one run to the next."""
    import subprocess

    kw = {} if rtol is None else {"rtol": rtol, "atol": rtol * atol_ratio}
    code = _COUNTED.format(tree=tree or os.path.dirname(HERE), here=HERE, name=name, kw=kw,
                           runs=runs)
    out = subprocess.run(["valgrind", "--tool=callgrind", "--instr-atstart=no",
                          "--callgrind-out-file=/dev/null", sys.executable, "-c", code],
                         capture_output=True, text=True, check=True, cwd=tree or os.getcwd(),
                         env=dict(os.environ, PYTHONHASHSEED="0", OPENBLAS_NUM_THREADS="1"))
    counted = [line for line in out.stderr.splitlines() if "Collected" in line]
    return int(counted[-1].split()[-1]) / runs / 1e6


def default_route(names, rtol, atol_ratio, repeats, before: str | None = None,
                  counted: bool = False) -> list[dict]:
    rows = []
    for name in names:
        if before is None:
            row = measure(name, rtol, atol_ratio, repeats)
        else:
            runs: dict[str, list[dict]] = {"now": [], "before": [], "before, defaults": []}
            for _ in range(repeats):
                runs["now"].append(_in_child(None, name, rtol, atol_ratio))
                runs["before"].append(_in_child(before, name, rtol, atol_ratio))
                runs["before, defaults"].append(_in_child(before, name, None, atol_ratio))
            row = dict(runs["now"][0], ms=statistics.median(r["ms"] for r in runs["now"]))
            for key in ("before", "before, defaults"):
                row[key] = dict(runs[key][0],
                                ms=statistics.median(r["ms"] for r in runs[key]))
            if counted:
                row["Minstr"] = instructions(None, name, rtol, atol_ratio)
                row["before"]["Minstr"] = instructions(before, name, rtol, atol_ratio)
        rows.append(row)
        print(f"{name:22s} {row['ms']:8.1f} ms  nfev {row['nfev']:7d}  "
              f"events {row['events']:4d}  error {row['error']:.1e}  | OUTDEL x20: "
              f"events {row['coarse events']:4d}  error {row['coarse error']:.1e}"
              + "".join(f"  | {k}: {row[k]['ms']:.1f} ms, error {row[k]['error']:.1e}, "
                        f"OUTDEL x20 events {row[k]['coarse events']}"
                        for k in ("before", "before, defaults") if k in row), flush=True)
    return rows


def _coarse_error(case, run) -> float:
    """The error on the rows a coarse run shares with the reference grid."""
    g, ref = case.ref()
    idx = np.searchsorted(g, run.t - 1e-9 * case.outdel)
    idx = np.clip(idx, 0, len(g) - 1)
    ok = np.abs(g[idx] - run.t) <= 1e-7 * case.outdel
    scales = case.scales()
    return max(float(np.max(np.abs(run[n][ok] - ref[n][idx[ok]]))) / (1e-12 + scales[n])
               for n in case.states)


# ------------------------------------------------------------------ equal error

LADDER = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)
# every RELERR of the ladder in one child (a first run each, then the least CPU time of
# `repeats`): the time and the error against the exact reference
_LADDER = """
import json, sys, time
sys.path.insert(0, {tree!r})
import amilpy
sys.path.insert(1, {here!r})
from cases import all_cases, error_on_grid
case = all_cases()[{name!r}]
model = amilpy.loads(case.text, case.name)
out = []
for rtol in {rtols!r}:
    kw = dict(rtol=rtol, atol=rtol * {atol_ratio!r})
    run = model.run(advice=False, **kw)[0]
    times = []
    for _ in range({repeats}):
        t0 = time.process_time()
        model.run(advice=False, **kw)
        times.append(time.process_time() - t0)
    out.append(dict(rtol=rtol, ms=1e3 * min(times), nfev=run.stats.get("nfev"),
                    error=error_on_grid(case, run.t, {{n: run[n] for n in case.states}})))
assert amilpy.__file__.startswith({tree!r})
print(json.dumps(out))
"""


def _ladder_child(tree: str, name: str, atol_ratio: float, repeats: int) -> list[dict]:
    import json
    import subprocess

    code = _LADDER.format(tree=tree, here=HERE, name=name, rtols=LADDER,
                          atol_ratio=atol_ratio, repeats=repeats)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=tree,
                         env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    return json.loads(out.stdout.strip().splitlines()[-1])


def _front(points: list[dict]) -> list[dict]:
    """The cheapest time for each error reached (a Pareto front), by falling error."""
    out, best = [], math.inf
    for p in sorted(points, key=lambda p: p["ms"]):
        if p["error"] < best:
            out.append(p)
            best = p["error"]
    return out


def time_at(front: list[dict], error: float) -> float | None:
    """The front's time at `error`, interpolated log-log (None outside it)."""
    f = sorted(front, key=lambda p: -p["error"])
    for a, b in zip(f, f[1:], strict=False):
        if b["error"] <= error <= a["error"]:
            w = (math.log(error / a["error"]) / math.log(b["error"] / a["error"])
                 if a["error"] != b["error"] else 0.0)
            return math.exp(math.log(a["ms"]) + w * math.log(b["ms"] / a["ms"]))
    return None


def equal_error(names, before: str, atol_ratio: float, repeats: int, rounds: int = 2
                ) -> list[dict]:
    """AUTO now and AUTO in `before` over the RELERR ladder, each tree a fresh child
    per model and round, the trees alternating; each point the least time over the
    rounds. Returns per model the two ladders and the ratio of the times at equal
    error (each decade from 1e-3 to 1e-9 both fronts reach)."""
    here = os.path.dirname(HERE)
    rows = []
    for name in names:
        runs: dict[str, list] = {"now": [], "before": []}
        for _ in range(rounds):
            runs["now"].append(_ladder_child(here, name, atol_ratio, repeats))
            runs["before"].append(_ladder_child(before, name, atol_ratio, repeats))
        ladders = {k: [dict(v[0][i], ms=min(r[i]["ms"] for r in v)) for i in range(len(LADDER))]
                   for k, v in runs.items()}
        fronts = {k: _front(v) for k, v in ladders.items()}
        ratios = {}
        for error in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9):
            a, b = time_at(fronts["now"], error), time_at(fronts["before"], error)
            if a is not None and b is not None:
                ratios[error] = (a, b)
        rows.append({"model": name, **ladders, "ratios": ratios})
        print(name, "  ".join(f"{e:.0e}: {a / b:.2f}" for e, (a, b) in ratios.items()),
              flush=True)
    return rows


# --------------------------------------------------------------------- candidates

def _model(case, rtol, atol):
    import amilpy
    from amilpy.run.plan import Options
    from amilpy.run.prepare import prepare

    model = amilpy.loads(case.text, case.name)
    p = prepare(model.ir, model.ir.runs[0], Options(rtol=rtol, atol=atol), model.cache)
    c, plan = p.code, p.plan
    m = [1.0] * len(plan.watched)
    z = list(c.z0)
    return c, plan, m, z


def candidates(names, rtol, atol_ratio, repeats) -> list[dict]:
    cases = all_cases()
    rows = []
    for name in names:
        row = {"model": name}
        for label, fn in _ways(cases[name], rtol, rtol * atol_ratio):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    seconds, nfev = _cpu(fn, repeats)
                    row[label] = (1e3 * seconds, nfev)
                except Exception as exc:  # noqa: BLE001 - a way that cannot run this model
                    row[label] = (math.nan, str(exc)[:40])
        rows.append(row)
        print(name, {k: (round(v[0], 1), v[1]) for k, v in row.items() if k != "model"},
              flush=True)
    return rows


def _ways(case, rtol: float, atol: float) -> list[tuple[str, object]]:
    """The candidate ways, as functions of no argument returning their evaluations."""
    from scipy.integrate import LSODA, odeint
    from scipy.integrate._odepack import lsoda as lsoda_c

    c, plan, m, z = _model(case, rtol, atol)
    y0 = np.array(c.y0, float)
    n = len(y0)
    T = plan.grid.times
    t_end = float(T[-1])
    rhs, surf, surf_v = c.rhs, c.surf, c.surf_v
    watch = list(plan.watch_idx) or list(range(len(plan.watched)))

    def f(t, y):
        return rhs(t, y.tolist(), m, z)

    def plain():
        ys, info = odeint(f, y0, T, rtol=rtol, atol=atol, tfirst=True, full_output=True,
                          mxstep=10**6)
        return int(info["nfe"][-1])

    def logged():
        log_t, log_y = [], []

        def g(t, y):
            yl = y.tolist()
            log_t.append(t)
            log_y.append(yl)
            return rhs(t, yl, m, z)
        ys, info = odeint(g, y0, T, rtol=rtol, atol=atol, tfirst=True, full_output=True,
                          mxstep=10**6)
        t = np.asarray(log_t)
        later = np.minimum.accumulate(t[::-1])[::-1]
        keep = np.flatnonzero((t <= np.append(later[1:], np.inf)) &
                              np.append(t[1:] != t[:-1], True))
        S = t[keep]
        SY = np.array([log_y[k] for k in keep.tolist()])
        if len(plan.watched):
            surf_v(S, list(SY.T), m, z)
        return int(info["nfe"][-1])

    def one_step():
        lrw = max(20 + 16 * n, 22 + 9 * n + n * n)
        rwork, iwork = np.zeros(lrw), np.zeros(20 + n, np.int32)
        iwork[5], iwork[7], iwork[8] = 10**6, 12, 5
        rwork[0] = t_end  # tcrit
        sd, si = np.zeros(240), np.zeros(48, np.int32)
        istate, t, y = 1, 0.0, y0.copy()
        while t < t_end:
            y, t, istate = lsoda_c(f, y, t, t_end, rtol, atol, 5, istate, rwork, iwork,
                                   None, 2, (), 1, (), sd, si)
            if istate < 0:
                raise RuntimeError(f"lsoda istate {istate}")
            if watch:
                surf(t, y.tolist(), m, z)
        return int(iwork[11])

    def scipy_class():
        s = LSODA(f, 0.0, y0, t_end, rtol=rtol, atol=atol)
        while s.status == "running":
            s.step()
            if watch:
                surf(s.t, s.y.tolist(), m, z)
        return s.nfev

    ways = [("odeint", plain), ("odeint+log", logged), ("lsoda 1-step", one_step),
            ("LSODA class", scipy_class)]
    try:
        from sksundae.cvode import CVODE
    except ImportError:
        return ways
    if watch:
        k = len(plan.watched)

        def cvode():
            def rhsfn(t, y, yp):
                yp[:] = rhs(t, y.tolist(), m, z)

            def events(t, y, e):
                e[:] = surf(t, y.tolist(), m, z)
            events.terminal = [False] * k
            solver = CVODE(rhsfn, rtol=rtol, atol=atol, eventsfn=events, num_events=k,
                           max_num_steps=10**6)
            sol = solver.solve(T, y0)
            return int(getattr(sol, "nfev", 0) or 0)
        ways.append(("CVODE roots", cvode))
    return ways


def markdown(table1, table2, args, table3=()) -> str:
    import platform

    import scipy

    import amilpy

    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    out = ["# Exact by default: the default route and the per-step watch\n",
           f"`{' '.join(['python', 'benchmarks/exactness.py'] + sys.argv[1:])}` - amilpy "
           f"from `{os.path.dirname(amilpy.__file__)}`, Python {platform.python_version()}, "
           f"SciPy {scipy.__version__}, NumPy {np.__version__}, load average {load}; CPU "
           f"time, median of {args.repeats}.\n",
           ]
    if table1:
        out += ["## The default route (METHOD AUTO)\n",
                "| model | settings | ms | evaluations | events | error | OUTDEL x20: events "
                "| error |", "|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in table1:
        out.append(f"| {r['model']} | {r['settings']} | {r['ms']:.1f} | {r['nfev']} | "
                   f"{r['events']} | {r['error']:.1e} | {r['coarse events']} | "
                   f"{r['coarse error']:.1e} |")
    if table1 and "before" in table1[0]:
        out += ["", f"## Before and after: the default route, `{args.before}` as before\n",
                "Each column a fresh process per round, the rounds alternating; `now / "
                "before`: the ratio of the times at the same RELERR.\n",
                "| model | now ms | before ms (same RELERR) | now / before | before: error "
                "| before: OUTDEL x20 events (of) | before at its defaults: settings | ms "
                "| error | OUTDEL x20 events |",
                "|---|---:|---:|---:|---:|---:|---|---:|---:|---:|"]
        for r in table1:
            b, d = r["before"], r["before, defaults"]
            out.append(f"| {r['model']} | {r['ms']:.1f} | {b['ms']:.1f} | "
                       f"{r['ms'] / b['ms']:.2f} | {b['error']:.1e} | {b['coarse events']} "
                       f"({r['events']}) | {d['settings']} | {d['ms']:.1f} | "
                       f"{d['error']:.1e} | {d['coarse events']} |")
        if "Minstr" in table1[0]:
            out += ["", "Instructions a run takes at the same RELERR (callgrind, `--instructions`:"
                    " the same count every time, where the CPU times above vary by a third "
                    "from one round to the next on this machine):\n",
                    "| model | now, M instructions | before | now / before |",
                    "|---|---:|---:|---:|"]
            for r in table1:
                b = r["before"]
                out.append(f"| {r['model']} | {r['Minstr']:.1f} | {b['Minstr']:.1f} | "
                           f"{r['Minstr'] / b['Minstr']:.2f} |")
    if table3:
        errors = sorted({e for r in table3 for e in r["ratios"]}, reverse=True)
        out += ["", f"## At equal error: AUTO now against `{args.before}` (`--equal-error`)\n",
                f"RELERR {', '.join(f'{x:g}' for x in LADDER)} (ABSERR = RELERR x "
                f"{args.atol_ratio:g}) on both, each a fresh child per model and round, the "
                f"trees alternating, the least CPU time of {args.repeats} runs over 2 rounds; "
                "each tree's time at an error read off its Pareto front (log-log): now ms / "
                "before ms = ratio, where both fronts reach that error.\n",
                "| model | " + " | ".join(f"error {e:.0e}" for e in errors) + " |",
                "|---|" + "---:|" * len(errors)]
        for r in table3:
            cells = [f"{r['ratios'][e][0]:.1f} / {r['ratios'][e][1]:.1f} = "
                     f"**{r['ratios'][e][0] / r['ratios'][e][1]:.2f}**"
                     if e in r["ratios"] else "-" for e in errors]
            out.append(f"| {r['model']} | " + " | ".join(cells) + " |")
        out += ["", "The ladders (RELERR: ms, error; now, then before):\n"]
        for r in table3:
            for k in ("now", "before"):
                out.append(f"- {r['model']}, {k}: " + ", ".join(
                    f"{p['rtol']:.0e}: {p['ms']:.1f} ms, {p['error']:.1e}" for p in r[k]))
    if table2:
        ways = [k for k in table2[0] if k != "model"]
        out += ["", f"## Watching every step: the candidates (RELERR {args.cand_rtol:g}, "
                "branches as at t = 0, no event handled)\n",
                "| model | " + " | ".join(f"{w} ms (evals)" for w in ways) + " |",
                "|---|" + "---:|" * len(ways)]
        for r in table2:
            out.append(f"| {r['model']} | " + " | ".join(
                f"{r[w][0]:.1f} ({r[w][1]})" if isinstance(r[w][1], int) else f"- ({r[w][1]})"
                for w in ways) + " |")
    return "\n".join(out) + "\n"


def main(argv=None) -> tuple[list[dict], list[dict]]:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--models", nargs="*", default=SHIPPED)
    p.add_argument("--rtol", type=float, default=None,
                   help="RELERR of table 1 (default: the listing's default)")
    p.add_argument("--atol-ratio", type=float, default=1e-3)
    p.add_argument("--cand-rtol", type=float, default=1e-10, help="RELERR of table 2")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--no-candidates", action="store_true")
    p.add_argument("--out", default=None, help="write exactness.md here")
    p.add_argument("--before", default=None,
                   help="a checkout of older amilpy code: its columns side by side")
    p.add_argument("--instructions", action="store_true",
                   help="with --before: also count each run's instructions (valgrind)")
    p.add_argument("--equal-error", action="store_true",
                   help="with --before: both trees over the RELERR ladder, the ratio of "
                   "the times at equal error")
    p.add_argument("--only-equal-error", action="store_true",
                   help="the equal-error table alone (with --before)")
    args = p.parse_args(argv)
    if args.only_equal_error:
        args.equal_error = True
        args.no_candidates = True
    t3 = equal_error(args.models, args.before, args.atol_ratio, args.repeats) \
        if args.equal_error and args.before else []
    t1 = [] if args.only_equal_error else default_route(
        args.models, args.rtol, args.atol_ratio, args.repeats, args.before, args.instructions)
    t2 = [] if args.no_candidates else candidates(args.models, args.cand_rtol, args.atol_ratio,
                                                  args.repeats)
    text = markdown(t1, t2, args, t3)
    print(text)
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        name = "exactness_equal_error.md" if args.only_equal_error else "exactness.md"
        with open(os.path.join(args.out, name), "w", encoding="utf-8") as fh:
            fh.write(text)
    return t1, t2


if __name__ == "__main__":
    main()
