"""Work-precision benchmark: amilpy's methods against hand-written SciPy, at equal error.

    OPENBLAS_NUM_THREADS=1 python benchmarks/work_precision.py            # everything
    python benchmarks/work_precision.py --models ex4_clutch --repeats 3
    python benchmarks/work_precision.py --quick                           # a smoke run

For every case (``benchmarks/cases.py``) and every route:

* amilpy AUTO, RKS, DOP853, LSODA, RADAU, BDF at rtol 1e-3 .. 1e-11, atol = rtol * (the
  smallest state scale of the model, i.e. max|y_ref| of its smallest state);
* amilpy RK4, EULER, TRAPZ at DELT = OUTDEL / 2**k (TIMER DELT added to the listing);
* the same equations hand-written as a plain Python function (floats: the solver's array
  is turned into a list with ``y.tolist()`` first, the fastest way to call such a
  function) and integrated by ``solve_ivp`` (RK45, DOP853, LSODA, Radau, BDF), ``odeint``
  and ``ode`` (dop853, vode/BDF, lsoda), each to the same output grid, split at the
  switches on TIME, integrating straight through the switches on states;
* when numba is importable, the compiled ceiling of the shipped models (``ceiling.py``:
  the hand-written equations and a DOP853 with events, all compiled by numba);

it records the wall time (median of ``--repeats`` runs, one run when it takes over 1 s;
the model is compiled before any timing, and amilpy's first run with its compilation is
reported separately), RHS evaluations, steps, events and

    error = max over the OUTDEL grid and the states of |y - y_ref| / (1e-12 + max|y_ref|)

against the reference (``tests/references`` for the shipped models, closed forms for the
core ones). Each route's work-precision line (its Pareto front: cheapest time for each
error reached) is interpolated log-log to read the time needed for errors 1e-3, 1e-6,
1e-9; the summary prints, per case and level, the fastest hand-written route, amilpy
AUTO's time and their ratio. Output in ``--out`` (default ``benchmarks/results``):
``work_precision.csv``, ``work_precision.md``, ``summary.csv`` and one
``wp_<case>.png`` per case.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import statistics
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import ROOT, Case, all_cases, error_on_grid, with_delt  # noqa: E402
from hybrids import hybrid_solve  # noqa: E402

AMILPY_METHODS = ["AUTO", "RKS", "DOP853", "LSODA", "RADAU", "BDF"]
FIXED_METHODS = ["RK4", "EULER", "TRAPZ"]
# the same ladder for both sides: a level one side reaches only at the last rung must
# not read as "not reached" for the other
TOLS = [10.0**-k for k in range(3, 13)]
HAND_TOLS = TOLS
HAND_ROUTES = ["ivp_RK45", "ivp_DOP853", "ivp_LSODA", "ivp_Radau", "ivp_BDF", "odeint",
               "ode_dop853", "ode_vode_bdf", "ode_lsoda"]
# with the switches on states as terminal events (cases that have a `hybrid`)
EVENT_ROUTES = ["ivp_RK45+ev", "ivp_DOP853+ev", "ivp_LSODA+ev", "ivp_Radau+ev"]
LEVELS = [1e-3, 1e-6, 1e-9]
SLOW = 4.0  # seconds: a route whose run takes longer stops tightening


def _median_time(fn, repeats: int):
    """(median seconds, last result) of ``repeats`` calls; one call if it is slow."""
    times, res = [], None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        res = fn()
        times.append(time.perf_counter() - t0)
        if times[-1] > 1.0:
            break
    return statistics.median(times), res


# --------------------------------------------------------------------------- amilpy

def first_run_cost(case: Case) -> dict:
    """Parse+check, first run (compiles) and a steady run, at the listing's defaults."""
    import amilpy

    t0 = time.perf_counter()
    model = amilpy.loads(case.text, case.name)
    t1 = time.perf_counter()
    model.run()
    t2 = time.perf_counter()
    steady, _ = _median_time(lambda: model.run(), 3)
    return {"case": case.name, "load_s": t1 - t0, "first_run_s": t2 - t1, "steady_run_s": steady}


PROBE_METHODS = ["RKS", "DOP853"]  # the explicit routes the advice probes after


def probe_cost(case: Case, rtol: float = 1e-6, repeats: int = 3) -> list[dict]:
    """What the stiffness-advice probe adds after a run of an explicit method: the run
    alone and the probe alone (`advice.stiffness_advice`, made to run whatever the
    run's length), each the median of repeats; `advice` whether it would run at all
    (the run took `advice.SLOW` seconds or more)."""
    import amilpy
    from amilpy.run import Options
    from amilpy.run import advice as advice_module

    threshold = getattr(advice_module, "SLOW", 0.0)  # (no such threshold before)

    def stiffness_advice(*args):
        advice_module.SLOW = 0.0
        try:
            return advice_module.stiffness_advice(*args)
        finally:
            advice_module.SLOW = threshold

    model = amilpy.loads(case.text, case.name)
    model.run()
    atol = rtol * case.atol_factor()
    spec = model.ir.runs[0]
    out = []
    for method in PROBE_METHODS:
        run_s, runs = _median_time(lambda m=method: model.run(method=m, rtol=rtol, atol=atol,
                                                             advice=False), repeats)
        opts = Options(method=method, rtol=rtol, atol=atol)
        probe_s, note = _median_time(lambda r=runs[0], o=opts: stiffness_advice(
            model.ir, spec, r, o, model.cache), repeats)
        out.append({"case": case.name, "method": method, "rtol": rtol, "run_s": run_s,
                    "probe_s": probe_s, "nfev": runs[0].stats.get("nfev"),
                    "advice": note is not None,
                    "probed": runs[0].stats.get("seconds", 0.0) >= threshold and
                    runs[0].stats.get("nfev", 0) >= advice_module.EXPENSIVE})
        print(f"  probe {case.name} {method}: run {run_s * 1e3:.3g} ms, probe "
              f"{probe_s * 1e3:.3g} ms", flush=True)
    return out


@dataclass
class Point:
    """One route at one setting: `run()` integrates once; `row(result)` measures it."""

    row0: dict
    run: Callable[[], object]
    row: Callable[[object], dict]
    times: list[float] = field(default_factory=list)


def amilpy_points(case: Case, tols, methods, fixed, ladder: int) -> list[list[Point]]:
    """Per route, its points from loose to tight (the model compiled before any timing)."""
    import amilpy

    model = amilpy.loads(case.text, case.name)
    model.run(advice=False)  # compile once for this set of constants
    if "COMPILED" in methods:
        model.run(method="COMPILED", advice=False)  # and its numba functions
    fac = case.atol_factor()

    def measured(runs) -> dict:
        r = runs[0]
        return dict(nfev=r.stats.get("nfev"), nsteps=r.stats.get("nsteps"),
                    events=len(r.events), status=str(r.status),
                    error=error_on_grid(case, r.t, {n: r[n] for n in case.states}))

    routes = []
    for method in methods:
        # the integration alone: the stiffness-advice probe is measured apart (probe_cost)
        routes.append([Point(
            {"case": case.name, "kind": "amilpy", "route": method, "rtol": rtol,
             "atol": rtol * fac, "delt": None},
            lambda m=method, r=rtol: model.run(method=m, rtol=r, atol=r * fac, advice=False),
            measured) for rtol in tols])
    for method in fixed:
        pts = []
        for k in range(ladder):
            delt = case.outdel / 2**k
            m = amilpy.loads(with_delt(case.text, delt), case.name)
            pts.append(Point({"case": case.name, "kind": "amilpy", "route": method,
                              "rtol": None, "atol": None, "delt": delt},
                             lambda m=m, meth=method: m.run(method=meth, advice=False),
                             measured))
        routes.append(pts)
    return routes


def hand_points(case: Case, tols, routes) -> list[list[Point]]:
    fac = case.atol_factor()

    def measured(res) -> dict:
        t, vals, nfev, nsteps = res
        return dict(nfev=nfev or None, nsteps=nsteps or None, events=0, status="finished",
                    error=error_on_grid(case, t, vals))

    out = []
    for route in routes:
        if route.endswith("+ev") and case.hybrid is None:
            continue
        out.append([Point({"case": case.name, "kind": "hand", "route": route, "rtol": rtol,
                           "atol": rtol * fac, "delt": None},
                          lambda route=route, rtol=rtol: hand_solve(case, route, rtol,
                                                                    rtol * fac),
                          measured) for rtol in tols])
    return out


def _time(point: Point):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        res = point.run()
        point.times.append(time.perf_counter() - t0)
    return res


def measure(routes: list[list[Point]], repeats: int) -> list[dict]:
    """Time every point `repeats` times, interleaved: the first pass goes route by route
    (a route stops tightening once a run takes over SLOW seconds or fails) and measures
    each result; every later pass runs all the points kept once more, in the same
    order, so a change of the machine's load falls on both sides of a ratio alike.
    The time of a point is the median of its passes (one pass past 1 s)."""
    rows, kept = [], []
    for points in routes:
        for p in points:
            row = dict(p.row0)
            try:
                row.update(p.row(_time(p)))
            except Exception as exc:  # noqa: BLE001 - a failing route is a result
                row.update(nfev=None, nsteps=None, events=None, error=math.inf,
                           status=f"ERROR {type(exc).__name__}: "
                                  f"{str(exc).splitlines()[0][:80] if str(exc) else ''}")
                p.times[:] = [math.nan]
            rows.append(row)
            kept.append(p)
            if not p.times[-1] < SLOW or row["status"].startswith("ERROR"):
                break
    for _ in range(max(0, repeats - 1)):
        for p in kept:
            if p.times[0] < 1.0:
                _time(p)
    for row, p in zip(rows, kept, strict=True):
        row["time"] = statistics.median(p.times)
        print(_fmt(row), flush=True)
    return rows


# --------------------------------------------------------------------------- hand-written

def _pieces(case: Case):
    """[(ta, tb, f, grid points in (ta, tb])] with f(t, y) taking the solver's array."""
    grid = case.grid()
    out, ta = [], 0.0
    for tb, f in case.segments():
        def g(t, y, f=f):
            return f(t, y.tolist())
        eps = 1e-9 * case.outdel
        pts = grid[(grid > ta + eps) & (grid <= tb + eps)]
        out.append((ta, tb, g, pts))
        ta = tb
    return out


def hand_solve(case: Case, route: str, rtol: float, atol: float):
    """Integrate the hand-written equations; (grid, {state: values}, nfev, nsteps). The
    rows go straight into one preallocated array, as a user who wants arrays writes it."""
    from scipy.integrate import ode, odeint, solve_ivp

    if route.endswith("+ev"):
        return hybrid_solve(case, route[4:-3], rtol, atol)
    y = np.array(case.y0, dtype=float)
    grid = case.grid()
    rows = np.empty((len(grid), len(y)))
    rows[0] = y
    filled = 1
    nfev = nsteps = 0
    for ta, tb, f, pts in _pieces(case):
        tail = [] if len(pts) and abs(pts[-1] - tb) <= 1e-12 * max(tb, 1) else [tb]
        want = np.concatenate([pts, tail])
        if route.startswith("ivp_"):
            sol = solve_ivp(f, (ta, tb), y, method=route[4:], t_eval=want, rtol=rtol, atol=atol)
            if sol.status < 0:
                raise RuntimeError(sol.message)
            seg = sol.y.T
            nfev += sol.nfev  # (solve_ivp does not report its step count)
        elif route == "odeint":
            seg, info = odeint(f, y, np.concatenate([[ta], want]), tfirst=True, rtol=rtol,
                               atol=atol, mxstep=10**7, full_output=True)
            if info["message"] != "Integration successful.":
                raise RuntimeError(info["message"])
            seg = seg[1:]
            nfev += int(info["nfe"][-1])
            nsteps += int(info["nst"][-1])
        else:
            name = route[4:]
            kw = {"method": "bdf"} if name == "vode_bdf" else {}
            r = ode(f).set_integrator("vode" if name == "vode_bdf" else name, rtol=rtol,
                                      atol=atol, nsteps=10**7, **kw)
            r.set_initial_value(y, ta)
            seg = np.empty((len(want), len(y)))
            for i, tp in enumerate(want):
                seg[i] = r.integrate(tp)
                if not r.successful():
                    raise RuntimeError(f"ode {name} failed at {tp}")
        rows[filled:filled + len(pts)] = seg[:len(pts)]
        filled += len(pts)
        y = seg[-1]
    return grid[:filled], {n: rows[:filled, i] for i, n in enumerate(case.states)}, nfev, \
        nsteps


# --------------------------------------------------------------------------- ceiling

CEILING_COMPILE: dict[str, float] = {}  # case: the ceiling's first call (compiles) [s]


def ceiling_points(case: Case, tols) -> list[list[Point]]:
    """The compiled ceiling (ceiling.py: the hand-written model and DOP853 compiled by
    numba), compiled before any timing; none when numba is not importable. Two drivers:
    rows from the dense output (numba), or every step ending on the next output point
    (numba_land: on the Exercise 4 drives, whose steps DOP853's stability holds above
    OUTDEL, the dense output inside those steps misses the current by 20-60 times the
    error at their ends: 6e-2 against 3e-3 at rtol 1e-3)."""
    try:
        import ceiling
    except ImportError:
        return []
    if case.name not in ceiling.MODELS:
        return []
    solver, CEILING_COMPILE[case.name] = ceiling.prepare(case)
    fac = case.atol_factor()
    return [[Point({"case": case.name, "kind": "ceiling", "route": route, "rtol": rtol,
                    "atol": rtol * fac, "delt": None},
                   lambda rtol=rtol, land=land: solver.run(rtol, rtol * fac, land),
                   solver.measured) for rtol in tols]
            for route, land in (("numba", False), ("numba_land", True))]


# --------------------------------------------------------------------------- analysis

def front(rows: list[dict]) -> list[tuple[float, float]]:
    """Pareto front (time, error): time increasing, error strictly decreasing."""
    pts = sorted((r["time"], r["error"]) for r in rows
                 if math.isfinite(r["time"]) and math.isfinite(r["error"]) and r["error"] > 0)
    out, best = [], math.inf
    for t, e in pts:
        if e < best:
            out.append((t, e))
            best = e
    return out


def time_at(rows: list[dict], level: float) -> float:
    """Time needed for error <= level, interpolated log-log on the front (inf: not reached)."""
    fr = front(rows)
    if not fr or fr[-1][1] > level:
        return math.inf
    if fr[0][1] <= level:
        return fr[0][0]
    for (t0, e0), (t1, e1) in zip(fr[:-1], fr[1:], strict=True):
        if e0 > level >= e1:
            s = (math.log(level) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + s * (math.log(t1) - math.log(t0)))
    return math.inf  # pragma: no cover


def by_route_time(by_route: dict, key: tuple[str, str], level: float) -> float:
    return time_at(by_route[key], level) if key in by_route else math.nan


def ceiling_time(by_route: dict, level: float) -> dict:
    """The compiled ceiling's time for the level: the faster of its routes (rows from
    the dense output, or steps ending on the output points)."""
    times = {k[1]: by_route_time(by_route, k, level) for k in by_route if k[0] == "ceiling"}
    best = min(times, key=times.get, default=None)
    return {"ceiling": times[best] if best else math.nan,
            "ceiling_route": best if best and math.isfinite(times[best]) else ""}


def summarize(case: Case, rows: list[dict], levels=LEVELS) -> list[dict]:
    by_route: dict[tuple[str, str], list[dict]] = {}
    for r in rows:
        by_route.setdefault((r["kind"], r["route"]), []).append(r)
    out = []
    for level in levels:
        hand = {k[1]: time_at(v, level) for k, v in by_route.items() if k[0] == "hand"}
        ami = {k[1]: time_at(v, level) for k, v in by_route.items() if k[0] == "amilpy"}
        best_hand = min(hand, key=hand.get) if hand else None
        best_ami = min(ami, key=ami.get) if ami else None
        auto = ami.get("AUTO", math.inf)
        th = hand[best_hand] if best_hand else math.inf
        out.append({
            "case": case.name, "level": level,
            "best_hand": best_hand if best_hand and math.isfinite(th) else "not reached",
            "hand_s": th, "auto_s": auto,
            "ratio": auto / th if math.isfinite(th) and math.isfinite(auto) else math.nan,
            "best_amilpy": best_ami if best_ami and math.isfinite(ami[best_ami]) else "-",
            "best_amilpy_s": ami[best_ami] if best_ami else math.inf,
            "min_err_hand": min((e for _, e in front(sum((v for k, v in by_route.items()
                                                          if k[0] == "hand"), []))),
                                default=math.inf),
            "min_err_auto": min((e for _, e in front(by_route.get(("amilpy", "AUTO"), []))),
                                default=math.inf),
            "compiled_s": ami.get("COMPILED", math.nan),
            **ceiling_time(by_route, level),
        })
    return out


def _g(x, fmt="{:.3g}") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return ""
    if isinstance(x, float):
        return "inf" if math.isinf(x) else fmt.format(x)
    return str(x)


def _fmt(r: dict) -> str:
    setting = f"rtol={_g(r['rtol'])}" if r["rtol"] else f"DELT={_g(r['delt'])}"
    return (f"  {r['case']:<22} {r['kind']:<6} {r['route']:<13} {setting:<14} "
            f"t={_g(r['time'] * 1e3 if r['time'] == r['time'] else math.nan)} ms "
            f"nfev={_g(r['nfev'])} steps={_g(r['nsteps'])} ev={_g(r['events'])} "
            f"err={_g(r['error'], '{:.2e}')} {r['status'] if r['status'] != 'finished' else ''}")


COLUMNS = ["case", "kind", "route", "rtol", "atol", "delt", "time", "nfev", "nsteps", "events",
           "error", "status"]


def write_outputs(out_dir: str, rows, summary, firsts, plot: bool = True, refs=(), probes=(),
                  load: str = "") -> None:
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "work_precision.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, COLUMNS)
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k) for k in COLUMNS})
    scols = ["case", "level", "best_hand", "hand_s", "auto_s", "ratio", "best_amilpy",
             "best_amilpy_s", "min_err_hand", "min_err_auto", "ceiling", "ceiling_route",
             "compiled_s"]
    with open(os.path.join(out_dir, "summary.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, scols)
        w.writeheader()
        for r in summary:
            w.writerow(r)
    with open(os.path.join(out_dir, "work_precision.md"), "w") as fh:
        fh.write(markdown(rows, summary, firsts, refs, probes, load))
    if plot:
        for case in sorted({r["case"] for r in rows}):
            plot_case(case, [r for r in rows if r["case"] == case],
                      os.path.join(out_dir, f"wp_{case}.png"))


def markdown(rows, summary, firsts, refs=(), probes=(), load: str = "") -> str:
    lines = []
    if load:
        lines += [f"Machine load (`uptime` load averages, 1/5/15 min): {load}", ""]
    if refs:
        lines += ["## References", "",
                  "| case | reference | checked against | largest difference (state) |",
                  "|---|---|---|---|"]
        lines += [f"| {r['case']} | {r['reference']} | {r['check']} | "
                  f"{_g(r['agreement'], '{:.1e}')} {r['state']} |" for r in refs]
        lines.append("")
    lines += ["## Equal-error summary (time to reach the error level; ratio = AUTO / fastest "
              "hand-written)", "",
             "| case | error | fastest hand-written | its time [ms] | amilpy AUTO [ms] | ratio "
             "| fastest amilpy | its time [ms] | best error hand | best error AUTO |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for s in summary:
        lines.append(
            f"| {s['case']} | {s['level']:.0e} | {s['best_hand']} | {_g(s['hand_s'] * 1e3)} | "
            f"{_g(s['auto_s'] * 1e3)} | {_g(s['ratio'], '{:.2f}')} | {s['best_amilpy']} | "
            f"{_g(s['best_amilpy_s'] * 1e3)} | {_g(s['min_err_hand'], '{:.1e}')} | "
            f"{_g(s['min_err_auto'], '{:.1e}')} |")
    if any(math.isfinite(x.get("ceiling", math.nan)) for x in summary):
        lines += ["", "ModelCode ceiling (hand-written RHS and integrator compiled by numba, "
                  "see ceiling.py): time to reach the level and AUTO / ceiling; the faster "
                  "of its two drivers: rows from the dense output (numba) or steps ending "
                  "on the output points (numba_land)", "",
                  "| case | error | ceiling [ms] | AUTO / ceiling | driver | "
                  "COMPILED [ms] | COMPILED / ceiling |",
                  "|---|---|---|---|---|---|---|"]
        for x in summary:
            c = x.get("ceiling", math.nan)
            ratio = x["auto_s"] / c if math.isfinite(c) and math.isfinite(x["auto_s"]) \
                else math.nan
            comp = x.get("compiled_s", math.nan)
            cratio = comp / c if math.isfinite(c) and math.isfinite(comp) else math.nan
            lines.append(f"| {x['case']} | {x['level']:.0e} | {_g(c * 1e3)} | "
                         f"{_g(ratio, '{:.1f}')} | {x.get('ceiling_route', '')} | "
                         f"{_g(comp * 1e3)} | {_g(cratio, '{:.1f}')} |")
        if CEILING_COMPILE:
            lines += ["", "The ceiling's compile (first call, not in its times; 0 when a model "
                      "with the same functions compiled it before) [s]: " + ", ".join(
                          f"{k} {v:.2f}" for k, v in CEILING_COMPILE.items())]
    if probes:
        lines += ["", "## The stiffness-advice probe (not in the times above)", "",
                  "| case | method | rtol | run [ms] | probe [ms] | probe / run | "
                  "probed after this run | advice |", "|---|---|---|---|---|---|---|---|"]
        lines += [f"| {p['case']} | {p['method']} | {p['rtol']:.0e} | {_g(p['run_s'] * 1e3)} "
                  f"| {_g(p['probe_s'] * 1e3)} | {p['probe_s'] / p['run_s']:.0%} | "
                  f"{'yes' if p.get('probed') else 'no (quicker than 1 s)'} | "
                  f"{'yes' if p['advice'] else 'no'} |" for p in probes]
    lines += ["", "## amilpy first-run cost (listing defaults)", "",
              "| case | parse+check [ms] | first run [ms] | steady run [ms] |", "|---|---|---|---|"]
    for f in firsts:
        lines.append(f"| {f['case']} | {f['load_s'] * 1e3:.1f} | {f['first_run_s'] * 1e3:.1f} | "
                     f"{f['steady_run_s'] * 1e3:.1f} |")
    lines += ["", "## All points", ""]
    for case in dict.fromkeys(r["case"] for r in rows):
        lines += [f"### {case}", "",
                  "| kind | route | rtol | DELT | time [ms] | nfev | steps | events | error "
                  "| status |", "|---|---|---|---|---|---|---|---|---|---|"]
        for r in rows:
            if r["case"] != case:
                continue
            lines.append(
                f"| {r['kind']} | {r['route']} | {_g(r['rtol'], '{:.0e}')} | "
                f"{_g(r['delt'], '{:.3g}')} | {_g(r['time'] * 1e3)} | {_g(r['nfev'])} | "
                f"{_g(r['nsteps'])} | {_g(r['events'])} | {_g(r['error'], '{:.2e}')} | "
                f"{r['status']} |")
        lines.append("")
    return "\n".join(lines) + "\n"


def plot_case(case: str, rows: list[dict], path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    routes = dict.fromkeys((r["kind"], r["route"]) for r in rows)
    for kind, route in routes:
        pts = [(r["time"], r["error"]) for r in rows if (r["kind"], r["route"]) == (kind, route)
               and math.isfinite(r["time"]) and math.isfinite(r["error"]) and r["error"] > 0]
        if not pts:
            continue
        t, e = zip(*pts, strict=True)
        style = dict(ls="-", marker="o") if kind == "amilpy" else dict(ls="--", marker="x")
        if route == "AUTO":
            style.update(lw=2.5, color="k")
        ax.loglog(e, np.array(t) * 1e3, label=f"{'amilpy ' if kind == 'amilpy' else ''}{route}",
                  ms=4, **style)
    ax.set_xlabel("error (max over grid and states, relative to the state's max)")
    ax.set_ylabel("wall time [ms]")
    ax.invert_xaxis()
    ax.set_title(f"work-precision: {case}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


# --------------------------------------------------------------------------- main

def main(models=None, tols=None, hand_tols=None, repeats: int = 3, ladder: int = 7,
         methods=None, fixed=None, hand_routes=None, out_dir: str | None = None,
         plot: bool = True, slow: float | None = None, probe: bool = True) -> dict:
    global SLOW
    if slow is not None:
        SLOW = slow
    cases = all_cases()
    names = models or list(cases)
    tols = tols or TOLS
    hand_tols = hand_tols or HAND_TOLS
    out_dir = out_dir or os.path.join(ROOT, "benchmarks", "results")
    rows, summary, firsts, refs, probes = [], [], [], [], []
    import amilpy  # one-time imports (SciPy, the grammar) are startup.py's subject
    amilpy.loads(cases["exp_decay"].text).run()
    load_before = _load()
    for name in names:
        case = cases[name]
        print(f"== {name}", flush=True)
        case.ref()
        agreement, state = case.agreement()
        refs.append({"case": name, "reference": case.reference_method,
                     "check": case.check_method or "-", "agreement": agreement,
                     "state": state})
        firsts.append(first_run_cost(case))
        if case.shipped and probe:
            probes += probe_cost(case, repeats=repeats)
        routes = amilpy_points(case, tols, AMILPY_METHODS if methods is None else methods,
                               FIXED_METHODS if fixed is None else fixed, ladder)
        routes += hand_points(case, hand_tols, HAND_ROUTES + EVENT_ROUTES
                              if hand_routes is None else hand_routes)
        routes += ceiling_points(case, hand_tols)
        rows_c = measure(routes, repeats)
        rows += rows_c
        summary += summarize(case, rows_c)
    load = f"{load_before} before, {_load()} after"
    write_outputs(out_dir, rows, summary, firsts, plot, refs, probes, load)
    print()
    print(markdown([], summary, firsts, refs, probes, load))
    return {"rows": rows, "summary": summary, "first": firsts, "out_dir": out_dir,
            "references": refs, "probes": probes}


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


SHIPPED = ["ex4_elastic", "ex4_clutch", "ex4_torque_meter", "hoist_backlash",
           "crank_slider_startup", "machine_unit"]


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="*", help="case names, or 'shipped' (default: all)")
    p.add_argument("--ratios", action="store_true",
                   help="the equal-error table only: the shipped models, AUTO against the "
                        "hand-written routes (and the ceiling), no other amilpy method")
    p.add_argument("--methods", nargs="*", help=f"amilpy methods (default {AMILPY_METHODS})")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--ladder", type=int, default=7, help="DELT = OUTDEL/2**k, k < this")
    p.add_argument("--quick", action="store_true", help="two tolerances, one repeat")
    p.add_argument("--slow", type=float, default=SLOW, help="stop a route past this [s]")
    p.add_argument("--out", default=None)
    a = p.parse_args()
    models = a.models
    if a.ratios or (models and models == ["shipped"]):
        models = [m for m in (models or SHIPPED) if m != "shipped"] or SHIPPED
    methods, fixed = a.methods, None
    if a.ratios:
        # AUTO, and the compiled route beside the compiled ceiling when numba is here
        from amilpy.compiled import available
        methods, fixed = ["AUTO", "COMPILED"] if available() else ["AUTO"], []
    if a.quick:
        main(models, tols=[1e-3, 1e-6], hand_tols=[1e-3, 1e-6], repeats=1, ladder=2,
             out_dir=a.out, slow=a.slow, methods=methods, fixed=fixed)
    else:
        main(models, repeats=a.repeats, ladder=a.ladder, out_dir=a.out, slow=a.slow,
             methods=methods, fixed=fixed)
