"""Step-point mode (METHOD EULER): amilpy's classic loop against the same loop written
by hand in plain Python, in one process.

    OPENBLAS_NUM_THREADS=1 python benchmarks/steppoint.py [--steps 100000] [--repeats 3]

Cases (each a listing and its recurrence written out on Python floats, the way a
competent user would write the Euler loop of the classic translators):

* ``switches``: a STEP, an FSW on a state, HSTRSS and a CSMP DELAY (the model of
  tests/test_steppoint.py), one row every 10 steps;
* ``relay``: a two-state oscillator with a relay (FSW on the velocity) that chatters
  from step to step, as it did in CSMP, one row every 100 steps.

For each: amilpy's run time (compiled beforehand; best of --repeats), per step, the
hand-written loop's, their ratio, and the largest difference of the rows (round-off:
the same arithmetic, maybe in another order). Writes ``steppoint.md`` in --out
(default ``benchmarks/results``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import amilpy  # noqa: E402

SWITCHES = """PARAM K = 2.0
X = INTGRL(1.0, -K*X + S + F)
S = STEP(0.25)
F = FSW(X - 0.9, 0.5, 0.0, -0.5)
H = HSTRSS(0.0, -0.05, 0.05, X)
D = DELAY(200, 0.2, X)
Y = INTGRL(0.0, H + D)
TIMER FINTIM = {fintim}, DELT = 0.001, PRDEL = 0.01
METHOD EULER
PRINT X, Y
END
"""


def switches_by_hand(n: int, delt: float = 0.001, every: int = 10):
    """The listing's loop on floats; the delay X(t - 0.2) is the value 200 steps back."""
    x, y, h = 1.0, 0.0, 0.0
    back = 200
    ring = [x] * (back + 1)
    rows = []
    for k in range(n + 1):
        t = k * delt
        h = min(x + 0.05, max(x - 0.05, h))
        d = ring[(k - back) % (back + 1)] if k >= back else ring[0 if k < back else 0]
        s = 0.0 if t < 0.25 else 1.0
        f = 0.5 if x < 0.9 else (0.0 if x == 0.9 else -0.5)
        if k % every == 0 or k == n:
            rows.append((t, x, y))
        ring[k % (back + 1)] = x
        x, y = x + delt * (-2.0 * x + s + f), y + delt * (h + d)
    return rows


RELAY = """PARAM K = 4.0, FC = 0.5
X = INTGRL(1.0, V)
V = INTGRL(0.0, -K*X - FSW(V, -FC, 0.0, FC))
TIMER FINTIM = {fintim}, DELT = 0.001, PRDEL = 0.1
METHOD EULER
PRINT X, V
END
"""


def relay_by_hand(n: int, delt: float = 0.001, every: int = 100):
    x, v = 1.0, 0.0
    rows = []
    for k in range(n + 1):
        if k % every == 0 or k == n:
            rows.append((k * delt, x, v))
        friction = -0.5 if v < 0 else (0.0 if v == 0 else 0.5)
        x, v = x + delt * v, v + delt * (-4.0 * x - friction)
    return rows


CASES = {"switches": (SWITCHES, switches_by_hand, ("X", "Y")),
         "relay": (RELAY, relay_by_hand, ("X", "V"))}


def _best(fn, repeats: int):
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(steps: int = 100_000, repeats: int = 3, out_dir: str | None = None) -> list[dict]:
    rows = []
    for name, (text, by_hand, names) in CASES.items():
        model = amilpy.loads(text.format(fintim=steps * 0.001), name=f"{name}.amil")
        model.run(advice=False)  # compiles
        t_amilpy, runs = _best(lambda m=model: m.run(advice=False), repeats)
        t_hand, ref = _best(lambda f=by_hand: f(steps), repeats)
        run = runs[0]
        ref = np.array(ref)
        diff = max(float(np.max(np.abs(run[n] - ref[:, i + 1]))) for i, n in enumerate(names))
        rows.append({"case": name, "steps": steps, "amilpy_s": t_amilpy,
                     "amilpy_us_per_step": 1e6 * t_amilpy / steps, "hand_s": t_hand,
                     "hand_us_per_step": 1e6 * t_hand / steps, "ratio": t_amilpy / t_hand,
                     "max_diff": diff, "rows": len(run.t), "events": len(run.events)})
    out_dir = out_dir or os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "steppoint.md"), "w", encoding="utf-8") as fh:
        fh.write("| case | steps | amilpy s | µs/step | by hand s | µs/step | ratio | "
                 "max diff | rows | events |\n|---|---|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            fh.write(f"| {r['case']} | {r['steps']} | {r['amilpy_s']:.3f} | "
                     f"{r['amilpy_us_per_step']:.2f} | {r['hand_s']:.3f} | "
                     f"{r['hand_us_per_step']:.2f} | {r['ratio']:.1f} | "
                     f"{r['max_diff']:.1e} | {r['rows']} | {r['events']} |\n")
    return rows


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--steps", type=int, default=100_000)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--out")
    a = p.parse_args()
    for row in main(a.steps, a.repeats, a.out):
        print(row)
