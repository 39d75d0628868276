"""Fitting (issue 24): time and evaluations of `Model.fit` with the Jacobian from
central differences of whole runs against the variational equations.

    OPENBLAS_NUM_THREADS=1 python benchmarks/fitting.py [--repeats 3] [--out DIR]

Cases: the decay of tests/test_fit.py (X0 and K, smooth), the ball on a
spring-dashpot floor (C and K, two switches a contact, data from the SciPy
version of the test), the sliding block (MU; a surface slides, so the variational
equations do not apply and the sensitivities fall back to differences) and the
shipped oral_dosing.csl (KA and KE on a log scale; the program's tangent is carried
through its DISCRETE doses, `analysis.program`). Each fit starts from the same
values; CPU time, the minimum of `--repeats`, in one process. Printed: seconds,
runs of the listing, Jacobians from the variational equations, the largest relative
error of the estimates against the values the data were made with, and how the
Jacobian was had.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

import numpy as np

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "tests"))


def cases(folder: str) -> list[tuple]:
    from test_fit import BALL, DECAY, FRICTION, _ball_scipy

    import amilpy

    def write(name, header, rows):
        path = os.path.join(folder, name)
        with open(path, "w") as fh:
            fh.write(header + "\n" + "".join(",".join(repr(float(v)) for v in r) + "\n"
                                              for r in rows))
        return path

    t = np.linspace(0.1, 2.0, 12)
    decay = write("decay.csv", "TIME,X", zip(t, 1.7 * np.exp(-0.8 * t), strict=True))
    tb = np.linspace(0.1, 1.45, 12)
    ball = write("ball.csv", "TIME,X", zip(tb, _ball_scipy(3.0, 300.0, tb), strict=True))
    mu, g = 0.2, 9.81
    stop = 2.0 / (mu * g)
    tf = np.arange(0.125, 1.5, 0.125)
    xf = np.where(tf < stop, 2.0 * tf - 0.5 * mu * g * tf ** 2,
                  2.0 * stop - 0.5 * mu * g * stop ** 2)
    friction = write("friction.csv", "TIME,X", zip(tf, xf, strict=True))
    td = np.array([1.0, 2.0, 4.0, 8.0, 11.5, 13.0, 18.0, 25.0, 36.5, 49.0, 60.0, 70.0])
    cp = sum(np.where(td >= d, 500.0 * 0.9 / (42.0 * (0.9 - 0.21)) *
                      (np.exp(-0.21 * (td - d)) - np.exp(-0.9 * (td - d))), 0.0)
             for d in (0.0, 12.0, 24.0, 36.0, 48.0, 60.0))
    dosing = write("dosing.csv", "T,CP", zip(td, cp, strict=True))
    return [
        ("decay (X0, K)", amilpy.loads(DECAY), decay, ["X0", "K=0:10"], {}, [1.7, 0.8]),
        ("ball on a floor (C, K)", amilpy.loads(BALL), ball, ["C=0.1:20", "K=50:2000"], {},
         [3.0, 300.0]),
        ("sliding block (MU)", amilpy.loads(FRICTION), friction, ["MU=0.05:1"], {}, [mu]),
        ("oral_dosing.csl (KA, KE)", amilpy.load(os.path.join(ROOT, "models", "examples",
                                                            "oral_dosing.csl")),
         dosing, ["KA=0.01:10", "KE=0.01:10"], {"log": ["KA", "KE"], "weights": "relative"},
         [0.9, 0.21]),
    ]


def main(repeats: int = 3, out_dir: str | None = None) -> str:
    rows = ["| case | Jacobian | CPU s | runs | variational Jacobians | max rel. error | how |",
            "|---|---|---:|---:|---:|---:|---|"]
    with tempfile.TemporaryDirectory() as folder:
        for label, model, data, free, kw, truth in cases(folder):
            kw = {"weights": "none", **kw}
            for how in ("differences", "sensitivities"):
                best, fit = float("inf"), None
                for _ in range(repeats):
                    start = time.process_time()
                    fit = model.fit(data, free, gradients=how, **kw)
                    best = min(best, time.process_time() - start)
                error = max(abs(e - v) / abs(v) for e, v in zip(fit.estimates, truth,
                                                                strict=True))
                rows.append(f"| {label} | {how} | {best:.2f} | {fit.runs} | {fit.jacobians} "
                            f"| {error:.1e} | {fit.gradients} |")
                print(rows[-1], flush=True)
    text = "\n".join(rows)
    if out_dir:
        os.makedirs(out_dir, exist_ok=True)
        with open(os.path.join(out_dir, "fitting.md"), "w", encoding="utf-8") as fh:
            fh.write("# Fitting: differences of runs against the variational equations\n\n"
                     "`python benchmarks/fitting.py --repeats 3 --out benchmarks/results`\n\n"
                     + text + "\n")
    return text


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    print()
    print(main(a.repeats, a.out))
