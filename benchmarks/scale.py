"""Scale: an N-mass chain, from the listing to the run, against hand-written NumPy.

    OPENBLAS_NUM_THREADS=1 python benchmarks/scale.py                 # N = 10 ... 1000
    python benchmarks/scale.py --sizes 200 1000 --repeats 3

The model: N masses in a line, each pair joined by a spring with a cubic term and a
damper, a sine force on the first mass; 3N - 1 statements (N - 1 coupling forces,
2N integrators), written in a shuffled order (the sort puts them right).

For every N: the front end's cost per statement (parse, check, codegen; it must stay
linear), then the run at rtol 1e-6 and 1e-9 (atol 1e-6 of that) by amilpy's AUTO,
LSODA, BDF and RADAU, and by hand-written routes a NumPy user would write (the right
side on arrays, slices for the neighbours): `solve_ivp` RK45, DOP853, LSODA, BDF and
Radau (the implicit ones with the chain's sparsity, `jac_sparsity`), and `odeint`
and LSODA with the band of the Jacobian (`ml = 3, mu = 2` in the interleaved order
X1, V1, X2, ...); the reference is DOP853 at rtol 1e-12 on the same NumPy right side. Error: max
over the output grid and states of |y - y_ref| / max|y_ref| of the state. Prints a
table and writes `scale.md` in `--out` (default `benchmarks/results`).
"""

from __future__ import annotations

import argparse
import math
import os
import random
import statistics
import sys
import time
import warnings

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import ROOT  # noqa: E402

M, K, K3, C, F0, W = 1.0, 1.0e4, 1.0e6, 5.0, 10.0, 5.0
FINTIM, OUTDEL = 2.0, 0.02


def chain_listing(n: int, seed: int = 1) -> str:
    """The N-mass chain as a listing, its statements shuffled."""
    lines = [f"F{i} = K*(X{i} - X{i + 1}) + K3*(X{i} - X{i + 1})**3 + C*(V{i} - V{i + 1})"
             for i in range(1, n)]
    lines += [f"X{i} = INTGRL(0.0, V{i})" for i in range(1, n + 1)]
    for i in range(1, n + 1):
        left = "F0*SIN(W*TIME)" if i == 1 else f"F{i - 1}"
        right = f" - F{i}" if i < n else ""
        lines.append(f"V{i} = INTGRL(0.0, ({left}{right})/M)")
    random.Random(seed).shuffle(lines)
    return "\n".join([f"TITLE {n}-MASS CHAIN",
                      f"PARAM M = {M!r}, K = {K!r}, K3 = {K3!r}, C = {C!r}, F0 = {F0!r}, "
                      f"W = {W!r}", "DYNAMIC", *("   " + s for s in lines),
                      f"TIMER FINTIM = {FINTIM!r}, OUTDEL = {OUTDEL!r}", "END"]) + "\n"


def numpy_rhs(n: int):
    """The chain's right side on arrays, states interleaved [X1, V1, X2, V2, ...]."""
    def f(t, s):
        x, v = s[0::2], s[1::2]
        d = x[:-1] - x[1:]
        force = K * d + K3 * d**3 + C * (v[:-1] - v[1:])
        acc = np.empty(n)
        acc[0] = F0 * math.sin(W * t)
        acc[1:] = force
        acc[:-1] -= force
        out = np.empty(2 * n)
        out[0::2] = v
        out[1::2] = acc / M
        return out
    return f


def chain_sparsity(n: int):
    from scipy.sparse import lil_matrix

    s = lil_matrix((2 * n, 2 * n))
    for i in range(n):
        s[2 * i, 2 * i + 1] = 1
        for j in (i - 1, i, i + 1):
            if 0 <= j < n:
                s[2 * i + 1, 2 * j] = 1
                s[2 * i + 1, 2 * j + 1] = 1
    return s.tocsc()


def hand(n: int, route: str, rtol: float, atol: float, grid: np.ndarray):
    """(states on the grid [rows, interleaved], nfev) of a hand-written route."""
    from scipy.integrate import odeint, solve_ivp

    f = numpy_rhs(n)
    y0 = np.zeros(2 * n)
    if route == "odeint":
        ys, info = odeint(f, y0, grid, tfirst=True, rtol=rtol, atol=atol, ml=3, mu=2,
                          full_output=True, mxstep=10**6)
        return ys, int(info["nfe"][-1])
    method = route[4:]
    kw = {"jac_sparsity": chain_sparsity(n)} if method in ("BDF", "Radau") else \
        {"lband": 3, "uband": 2} if method == "LSODA" else {}
    sol = solve_ivp(f, (0.0, grid[-1]), y0, method=method, t_eval=grid, rtol=rtol,
                    atol=atol, **kw)
    return sol.y.T, sol.nfev


HAND = ["ivp_RK45", "ivp_DOP853", "ivp_LSODA", "ivp_BDF", "ivp_Radau", "odeint"]
AMILPY = ["AUTO", "LSODA", "BDF", "RADAU"]


def _timed(fn, repeats: int):
    times, res = [], None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        res = fn()
        times.append(time.perf_counter() - t0)
        if times[-1] > 5.0:
            break
    return statistics.median(times), res


def front_end(n: int) -> dict:
    """Parse, check and codegen times per statement."""
    from amilpy.check import check
    from amilpy.parse import parse
    from amilpy.run import prepare

    text = chain_listing(n)
    statements = 3 * n - 1
    t0 = time.perf_counter()
    program = parse(text, "chain")
    t1 = time.perf_counter()
    model = check(program, "chain")
    t2 = time.perf_counter()
    prepare(model, model.runs[0])
    t3 = time.perf_counter()
    return {"n": n, "statements": statements, "parse_ms": (t1 - t0) * 1e3 / statements,
            "check_ms": (t2 - t1) * 1e3 / statements, "codegen_ms": (t3 - t2) * 1e3 / statements}


def error(n: int, ys: np.ndarray, ref: np.ndarray) -> float:
    scale = np.max(np.abs(ref), axis=0) + 1e-12
    if ys.shape != ref.shape or not np.all(np.isfinite(ys)):
        return math.inf
    return float(np.max(np.abs(ys - ref) / scale))


def run_size(n: int, tols, repeats: int, slow: float) -> list[dict]:
    import amilpy

    grid = np.linspace(0.0, FINTIM, int(round(FINTIM / OUTDEL)) + 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from scipy.integrate import solve_ivp

        ref = solve_ivp(numpy_rhs(n), (0.0, FINTIM), np.zeros(2 * n), method="DOP853",
                        t_eval=grid, rtol=1e-12, atol=1e-15).y.T
    model = amilpy.loads(chain_listing(n), "chain")
    order = []  # the listing's states in the interleaved order
    for i in range(1, n + 1):
        order += [f"X{i}", f"V{i}"]
    model.run(advice=False, outputs=order)  # compiled before any timing
    rows = []
    stopped: set[str] = set()
    for rtol in tols:
        atol = rtol * 1e-6
        for method in AMILPY:
            if ("amilpy", method) in stopped:
                continue
            secs, runs = _timed(lambda m=method, r=rtol, a=atol: model.run(
                method=m, rtol=r, atol=a, advice=False, outputs=order), repeats)
            r = runs[0]
            ys = np.column_stack([r[name] for name in order])
            rows.append({"n": n, "kind": "amilpy", "route": method, "rtol": rtol, "time": secs,
                         "nfev": r.stats["nfev"], "error": error(n, ys, ref)})
            print(_fmt(rows[-1]), flush=True)
            if secs > slow:
                stopped.add(("amilpy", method))
        for route in HAND:
            if ("hand", route) in stopped:
                continue
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                secs, (ys, nfev) = _timed(lambda r=route, rt=rtol, at=atol: hand(
                    n, r, rt, at, grid), repeats)
            rows.append({"n": n, "kind": "hand", "route": route, "rtol": rtol, "time": secs,
                         "nfev": nfev, "error": error(n, ys, ref)})
            print(_fmt(rows[-1]), flush=True)
            if secs > slow:
                stopped.add(("hand", route))
    return rows


def _fmt(r: dict) -> str:
    return (f"  N={r['n']:<5} {r['kind']:<6} {r['route']:<10} rtol={r['rtol']:.0e} "
            f"{r['time'] * 1e3:9.1f} ms  nfev={r['nfev']:<8} err={r['error']:.1e}")


def markdown(fronts: list[dict], rows: list[dict], load: str) -> str:
    lines = [f"Machine load (`uptime` load averages): {load}", "",
             "## Front end per statement [ms]", "",
             "| N | statements | parse | check | codegen |", "|---|---|---|---|---|"]
    lines += [f"| {f['n']} | {f['statements']} | {f['parse_ms']:.3f} | {f['check_ms']:.3f} | "
              f"{f['codegen_ms']:.3f} |" for f in fronts]
    lines += ["", "## Runs (time [ms], RHS evaluations, error)", "",
              "| N | rtol | route | time [ms] | nfev | error |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['n']} | {r['rtol']:.0e} | {r['kind']} {r['route']} | "
                     f"{r['time'] * 1e3:.1f} | {r['nfev']} | {r['error']:.1e} |")
    lines += ["", "## AUTO against the fastest hand-written route at the same tolerance", "",
              "Errors beside the times: a route that is faster but less accurate than AUTO "
              "at a tolerance is marked (less accurate).", "",
              "| N | rtol | AUTO [ms] | its error | fastest hand route (its error) | its time "
              "[ms] | ratio |", "|---|---|---|---|---|---|---|"]
    for (n, rtol) in dict.fromkeys((r["n"], r["rtol"]) for r in rows):
        auto = next(r for r in rows if (r["n"], r["rtol"], r["route"]) == (n, rtol, "AUTO"))
        hands = [r for r in rows if r["kind"] == "hand" and r["n"] == n and r["rtol"] == rtol
                 and math.isfinite(r["error"])]
        best = min(hands, key=lambda r: r["time"], default=None)
        if best is None:
            continue
        worse = " (less accurate)" if best["error"] > 2 * auto["error"] else ""
        lines.append(f"| {n} | {rtol:.0e} | {auto['time'] * 1e3:.1f} | {auto['error']:.1e} | "
                     f"{best['route']} ({best['error']:.1e}){worse} | {best['time'] * 1e3:.1f} "
                     f"| {auto['time'] / best['time']:.2f} |")
    return "\n".join(lines) + "\n"


def main(sizes=(10, 50, 200, 1000), tols=(1e-6, 1e-9), repeats: int = 3,
         slow: float = 30.0, out_dir: str | None = None) -> dict:
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    fronts = [front_end(n) for n in sizes]
    for f in fronts:
        print(f"N={f['n']}: parse {f['parse_ms']:.3f}, check {f['check_ms']:.3f}, codegen "
              f"{f['codegen_ms']:.3f} ms per statement", flush=True)
    rows = []
    for n in sizes:
        rows += run_size(n, tols, repeats, slow)
    load = f"{load} before, {' '.join(f'{x:.2f}' for x in os.getloadavg())} after"
    text = markdown(fronts, rows, load)
    out_dir = out_dir or os.path.join(ROOT, "benchmarks", "results")
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "scale.md"), "w") as fh:
        fh.write(text)
    print(text)
    return {"front": fronts, "rows": rows}


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="*", default=[10, 50, 200, 1000])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--slow", type=float, default=30.0, help="stop a route past this [s]")
    p.add_argument("--out", default=None)
    a = p.parse_args()
    main(a.sizes, repeats=a.repeats, slow=a.slow, out_dir=a.out)
