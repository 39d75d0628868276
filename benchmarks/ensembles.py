"""Ensembles (issue 25 point 4): the cost of one Monte Carlo member against one
`Model.run()` of the same listing, and against what a competent user would write
by hand for the same ensemble.

    OPENBLAS_NUM_THREADS=1 python benchmarks/ensembles.py [--members 1000] [--repeats 3]

oral_dosing.csl (KE and VD lognormal, 72 h, 6 doses every 12 h):
  amilpy montecarlo    Model.montecarlo, one worker (--jobs 1)
  Model.run            one run per member, the listing's defaults
  odeint per member    a loop over the members, each integrated dose to dose by
                       odeint, CP on the same 0.5 h grid
  odeint stacked       every member at once: one odeint over 2N states with a NumPy
                       right-hand side (possible because the doses come at the same
                       instants for every member), tolerances divided by sqrt(2N) so
                       that no member is integrated less accurately than alone
Both hand-written routes at RTOL 1e-6 (ATOL 1e-9) and at 1e-11 (1e-14), which
reaches the error amilpy's defaults give this listing.
The error is the largest relative error of CP over the grid and the members
against the closed form (the superposition of one Bateman curve per dose).

Two compartments (an infusion, CSMP form, KE lognormal and K12 uniform, 24 h): a
listing no member of which switches on its own, so amilpy integrates the members
at once (`amilpy.batch.stacked`), against the members one by one, Model.run and
the stacked odeint by hand (max-norm error test: no tolerance scaling needed);
the error of C1(24 h) against the closed form.

hoist_backlash.amil (ZETA uniform, 5 s, 111 contact edges a run): amilpy
montecarlo against Model.run (no stacked hand-written route: each member meets
the gap's edges at its own instants). With numba installed (the [fast] extra) the
members of a listing that names no METHOD run on METHOD COMPILED, one by one.

Printed: seconds per member (the minimum of --repeats, in one process), the
factor against Model.run, and the error.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time

import numpy as np

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DOSES = (0.0, 12.0, 24.0, 36.0, 48.0, 60.0)
DOSE, KA, TSTOP, CINT = 500.0, 1.2, 72.0, 0.5
# the hand-written routes at a plain tolerance and at one that reaches amilpy's error
TOLERANCES = ((1e-6, 1e-9), (1e-11, 1e-14))


def draws(n: int) -> tuple[np.ndarray, np.ndarray]:
    import amilpy  # noqa: F401 - the same draws as the Monte Carlo's
    from amilpy.batch.distributions import parse_dist, sample

    d = {"KE": parse_dist("KE", "lognormal(-1.754, 0.25)"),
         "VD": parse_dist("VD", "lognormal(3.738, 0.2)")}
    s = sample(d, n, seed=1)
    return s["KE"], s["VD"]


def exact(ke: np.ndarray, vd: np.ndarray, t: np.ndarray) -> np.ndarray:
    """CP(t) per member: one Bateman curve per dose given before or at t."""
    out = np.zeros((len(ke), len(t)))
    for d in DOSES:
        tau = np.clip(t - d, 0.0, None)[None, :]
        k = ke[:, None]
        out += np.where(t[None, :] >= d, DOSE * KA / (vd[:, None] * (KA - k)) *
                        (np.exp(-k * tau) - np.exp(-KA * tau)), 0.0)
    return out


def odeint_each(ke, vd, t, rtol, atol):
    from scipy.integrate import odeint

    out = np.empty((len(ke), len(t)))
    for m in range(len(ke)):
        k = float(ke[m])

        def f(y, _t, k=k):
            return [-KA * y[0], KA * y[0] - k * y[1]]
        y = np.array([0.0, 0.0])
        rows = []
        for i, d in enumerate(DOSES):
            y[0] += DOSE
            end = DOSES[i + 1] if i + 1 < len(DOSES) else TSTOP
            seg = t[(t >= d) & (t < end)] if end < TSTOP else t[t >= d]
            grid = np.concatenate([seg, [end]]) if seg[-1] < end else seg
            sol = odeint(f, y, grid, rtol=rtol, atol=atol)
            rows.append(sol[:len(seg), 1])
            y = sol[-1].copy()
        out[m] = np.concatenate(rows) / vd[m]
    return out


def odeint_stacked(ke, vd, t, rtol, atol):
    from scipy.integrate import odeint

    n = len(ke)
    scale = np.sqrt(2 * n)

    def f(y, _t):
        ag, ab = y[:n], y[n:]
        return np.concatenate([-KA * ag, KA * ag - ke * ab])
    y = np.zeros(2 * n)
    rows = []
    for i, d in enumerate(DOSES):
        y[:n] += DOSE
        end = DOSES[i + 1] if i + 1 < len(DOSES) else TSTOP
        seg = t[(t >= d) & (t < end)] if end < TSTOP else t[t >= d]
        grid = np.concatenate([seg, [end]]) if seg[-1] < end else seg
        sol = odeint(f, y, grid, rtol=rtol / scale, atol=atol / scale)
        rows.append(sol[:len(seg), n:])
        y = sol[-1].copy()
    return (np.concatenate(rows).T) / vd[:, None]


def listing_two() -> str:
    """The two-compartment listing of tests/test_montecarlo.py (one copy of it)."""
    sys.path.insert(0, os.path.join(ROOT, "tests"))
    from test_montecarlo import TWO_COMPARTMENTS

    return TWO_COMPARTMENTS


def two_exact(ke: np.ndarray, k12: np.ndarray) -> np.ndarray:
    """C1(24 h) per member: x(T) = A^-1 (e^{AT} - I) b."""
    from scipy.linalg import expm

    out = np.empty(len(ke))
    for k, (e, q) in enumerate(zip(ke, k12, strict=True)):
        a = np.array([[-(q + e), 0.3], [q, -0.3]])
        out[k] = np.linalg.solve(a, (expm(24.0 * a) - np.eye(2)) @ [10.0, 0.0])[0] / 5.0
    return out


def stacked_case(amilpy, n: int, repeats: int) -> None:
    """A listing none of whose members switches on its own: stacked against one by
    one, Model.run and the hand-written stacked odeint."""
    import tempfile

    from scipy.integrate import odeint

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "two.amil")
        with open(path, "w") as fh:
            fh.write(listing_two())
        model = amilpy.load(path)
        model.run(advice=False)
        dists = {"KE": "lognormal(-1.6, 0.3)", "K12": "uniform(0.3, 0.7)"}
        rows = []
        from amilpy import compiled

        alone = "  one by one" + (" (COMPILED)" if compiled.available() else "")
        for label, stacked in (("amilpy montecarlo", True), (alone, False)):
            sec, mc = best(lambda s=stacked: model.montecarlo(
                dists, runs=n, seed=1, outputs=["C1"], stacked=s), repeats)
            ref = two_exact(mc.samples["KE"], mc.samples["K12"])
            rows.append((label, sec / n, float(np.max(np.abs(mc.final[:, 0] - ref) / ref))))
        ke, k12 = mc.samples["KE"], mc.samples["K12"]
        ref = two_exact(ke, k12)
        sec_run, got = best(lambda: [model.run(advice=False, outputs=["C1"], KE=float(a),
                                               K12=float(b))[0]
                                     for a, b in zip(ke[:100], k12[:100], strict=True)],
                            repeats)
        per_run = sec_run / 100
        rows.insert(1, ("Model.run", per_run, float(np.max(
            np.abs(np.array([r["C1"][-1] for r in got]) - ref[:100]) / ref[:100]))))
        t = np.arange(0.0, 24.0 + 1e-9, 0.5)
        for rtol, atol in TOLERANCES:
            def hand(r=rtol, a=atol):
                def f(y, _t):
                    a1, a2 = y[:n], y[n:]
                    return np.concatenate([10.0 - (k12 + ke) * a1 + 0.3 * a2,
                                           k12 * a1 - 0.3 * a2])
                return odeint(f, np.zeros(2 * n), t, rtol=r, atol=a)[-1, :n] / 5.0
            sec, out = best(hand, repeats)
            rows.append((f"odeint stacked {rtol:.0e}", sec / n,
                         float(np.max(np.abs(out - ref) / ref))))
    print(f"\ntwo compartments (CSMP form, no switch), {n} members; CPU seconds per member")
    print(f"{'route':<28}{'s/member':>12}{'x Model.run':>13}{'max rel err':>13}")
    for name, s, err in rows:
        print(f"{name:<28}{s:12.2e}{s / per_run:13.3f}{err:13.1e}")


def best(fn, repeats: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeats):
        t0 = time.process_time()
        out = fn()
        times.append(time.process_time() - t0)
    return min(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--members", type=int, default=1000)
    ap.add_argument("--hoist-members", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    sys.path.insert(0, ROOT)
    import amilpy

    n = args.members
    ke, vd = draws(n)
    t = np.arange(0.0, TSTOP + 1e-9, CINT)
    ref = exact(ke, vd, t)
    model = amilpy.load(os.path.join(ROOT, "models", "examples", "oral_dosing.csl"))
    model.run(advice=False)  # (compiled once, as every route's first call)
    dists = {"KE": "lognormal(-1.754, 0.25)", "VD": "lognormal(3.738, 0.2)"}

    def mc():
        return model.montecarlo(dists, runs=n, seed=1, outputs=["CP"])

    def runs():
        return [model.run(advice=False, outputs=["CP"], KE=float(a), VD=float(b))[0]
                for a, b in zip(ke[:100], vd[:100], strict=True)]

    rows = []
    sec, result = best(mc, args.repeats)
    mc_err = float(np.max(np.abs(result.final[:, 0] - ref[:, -1]) / ref[:, -1]))
    rows.append(("amilpy montecarlo", sec / n, mc_err))
    sec_run, got = best(runs, args.repeats)
    per_run = sec_run / 100
    run_err = max(float(np.max(np.abs(r["CP"] - ref[k]) / np.maximum(ref[k], 1e-12)
                               * (ref[k] > 0))) for k, r in enumerate(got))
    rows.append(("Model.run", per_run, run_err))
    for rtol, atol in TOLERANCES:
        sec, out = best(lambda r=rtol, a=atol: odeint_each(ke[:100], vd[:100], t, r, a),
                        args.repeats)
        rows.append((f"odeint per member {rtol:.0e}", sec / 100,
                     float(np.max(np.abs(out - ref[:100])[:, 1:] / ref[:100, 1:]))))
        sec, out = best(lambda r=rtol, a=atol: odeint_stacked(ke, vd, t, r, a), args.repeats)
        rows.append((f"odeint stacked {rtol:.0e}", sec / n,
                     float(np.max(np.abs(out - ref)[:, 1:] / ref[:, 1:]))))
    print(f"oral_dosing.csl, {n} members (Model.run and odeint per member: 100 of them); "
          "CPU seconds per member")
    print(f"{'route':<28}{'s/member':>12}{'x Model.run':>13}{'max rel err':>13}")
    for name, s, err in rows:
        print(f"{name:<28}{s:12.2e}{s / per_run:13.3f}{err:13.1e}")

    stacked_case(amilpy, n, args.repeats)

    hoist = amilpy.load(os.path.join(ROOT, "models", "hoist_backlash.amil"))
    hoist.run(advice=False)
    h = args.hoist_members
    sec_mc, _ = best(lambda: hoist.montecarlo({"ZETA": "uniform(0.004, 0.006)"}, runs=h,
                                              seed=1, outputs=["Y"]), args.repeats)
    alone = min(h, 20)  # (Model.run: the cost of a run does not depend on how many)
    sec_run, _ = best(lambda: [hoist.run(advice=False, outputs=["Y"], ZETA=0.004 + 0.0002 * k)
                               for k in range(alone)], args.repeats)
    per_run = sec_run / alone
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\nhoist_backlash.amil, {h} members (Model.run: {alone} of them); CPU seconds "
          f"per member; this process's peak memory {peak:.0f} MB")
    print(f"{'amilpy montecarlo':<28}{sec_mc / h:12.2e}{sec_mc / h / per_run:13.3f}")
    print(f"{'Model.run':<28}{per_run:12.2e}{1.0:13.3f}")


if __name__ == "__main__":
    main()
