"""METHOD COMPILED (the [fast] extra): what it costs to start, and when it pays.

    OPENBLAS_NUM_THREADS=1 python benchmarks/compiled.py [--models ...] [--repeats 5]
                                                          [--long 20] [--out DIR]

For every shipped model:

* **start-up**, each in a fresh process: `import numba`; the kernel loaded from
  numba's cache; the model's own functions compiled (an empty model cache) and
  loaded (a warm one); the first run, end to end, both ways;
* **per run**, in this process, warm: AUTO and COMPILED at RELERR 1e-3 / 1e-6 /
  1e-9 (ABSERR = RELERR times the smallest state scale, as in `work_precision.py`),
  median of `--repeats`, with the error against the
  benchmark's exact references (`cases.py`), evaluations and events;
* **long runs** (`--long` times each model's FINTIM, RELERR 1e-6; the crank-slider
  stops at its FINISH): AUTO, COMPILED and the compiled ceiling (`ceiling.py`, the
  model and DOP853 written by hand for numba) per simulated second, and the
  **break-even**: the simulated time after which COMPILED's start-up is repaid by
  its lower cost per simulated second.

Nothing here asserts a time; `tests/test_benchmarks.py` runs it on a tiny setting.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from cases import ROOT, all_cases, error_on_grid  # noqa: E402

SHIPPED = ["ex4_elastic", "ex4_clutch", "ex4_torque_meter", "hoist_backlash",
           "crank_slider_startup", "machine_unit"]
TOLS = [1e-3, 1e-6, 1e-9]

_PROBE = """
import os, sys, time
t0 = time.perf_counter()
import numba
t1 = time.perf_counter()
from amilpy.compiled import kernel
t2 = time.perf_counter()
import amilpy
from amilpy.run import prepare
from amilpy.compiled import kernel_for
m = amilpy.load(sys.argv[1])
c = prepare(m.ir, m.ir.runs[0]).code
t3 = time.perf_counter()
k = kernel_for(c)
t4 = time.perf_counter()
assert not isinstance(k, str), k
m.run(method="COMPILED", advice=False)
t5 = time.perf_counter()
print(t1 - t0, t2 - t1, t4 - t3, t5 - t4)
"""


def startup(path: str, cache: str) -> list[float]:
    """(import numba, load the kernel, the model's functions, the first run) [s]."""
    env = dict(os.environ, AMILPY_CACHE=cache)
    out = subprocess.run([sys.executable, "-c", _PROBE, path], env=env, capture_output=True,
                         text=True, check=True, cwd=ROOT)
    return [float(x) for x in out.stdout.split()]


def timed(model, repeats: int, **kw) -> tuple[float, object]:
    times, run = [], None
    for _ in range(repeats):
        start = time.process_time()
        run, = model.run(advice=False, **kw)
        times.append(time.process_time() - start)
    return statistics.median(times), run


def ceiling_long(case, fintim: float, rtol: float, repeats: int) -> float:
    """The compiled ceiling's time for a run of `fintim` (its own grid and breaks)."""
    import ceiling
    import numpy as np

    if case.name not in ceiling.MODELS:
        return math.nan
    c, _ = ceiling.prepare(case)
    n = int(math.floor(fintim / case.outdel * (1 + 1e-12) + 1e-9))
    c.grid = case.outdel * np.arange(n + 1)
    c.breaks = np.append(c.breaks[c.breaks < case.fintim], fintim)
    times = []
    for _ in range(repeats):
        start = time.process_time()
        c.run(rtol, rtol * case.atol_factor())
        times.append(time.process_time() - start)
    return statistics.median(times)


def main(models=None, repeats: int = 5, long: float = 20.0, out_dir: str | None = None,
         tols=None) -> dict:
    import amilpy
    from amilpy import compiled

    if not compiled.available():
        print("numba is not installed: pip install 'amilpy[fast]'")
        return {}
    cases = all_cases()
    names = models or SHIPPED
    tols = tols or TOLS
    lines = ["# METHOD COMPILED", "",
             f"{os.cpu_count()} CPUs, load {' '.join(f'{x:.2f}' for x in os.getloadavg())}; "
             f"process time, median of {repeats}.", "",
             "## Start-up, each in a fresh process [s]", "",
             "| model | import numba | kernel (cached) | model compiled | model cached | "
             "first run, compiled | first run, cached |", "|---|---|---|---|---|---|---|"]
    result = {"startup": {}, "runs": [], "break_even": {}}
    for name in names:
        path = os.path.join(ROOT, "models", f"{name}.amil")
        with tempfile.TemporaryDirectory() as cache:
            cold = startup(path, cache)
            warm = startup(path, cache)
        result["startup"][name] = (cold, warm)
        lines.append(f"| {name} | {cold[0]:.2f} | {cold[1]:.2f} | {cold[2]:.2f} | "
                     f"{warm[2]:.2f} | {sum(cold):.2f} | {sum(warm):.2f} |")
    lines += ["", "## Per run, warm (error against the exact references)", "",
              "| model | RELERR | AUTO [ms] | its error | COMPILED [ms] | its error | "
              "AUTO / COMPILED | nfev AUTO / COMPILED | events |",
              "|---|---|---|---|---|---|---|---|---|"]
    for name in names:
        case = cases[name]
        grid, ref = case.ref()
        model = amilpy.loads(case.text, name=f"{name}.amil")
        model.run(method="COMPILED", advice=False)  # compiled outside the timing
        for tol in tols:
            row = {"case": name, "rtol": tol}
            for method in ("AUTO", "COMPILED"):
                t, run = timed(model, repeats, method=method, rtol=tol,
                               atol=tol * case.atol_factor())
                err = error_on_grid(case, run.t, {s: run[s] for s in case.states})
                row[method] = (t, err, int(run.stats["nfev"]), len(run.events))
            result["runs"].append(row)
            a, c = row["AUTO"], row["COMPILED"]
            lines.append(f"| {name} | {tol:.0e} | {a[0] * 1e3:.2f} | {a[1]:.1e} | "
                         f"{c[0] * 1e3:.2f} | {c[1]:.1e} | {a[0] / c[0]:.2f} | "
                         f"{a[2]} / {c[2]} | {c[3]} |")
    lines += ["", f"## Long runs ({long:g} x FINTIM, RELERR 1e-6) and the break-even", "",
              "| model | simulated [s] | AUTO [ms per simulated s] | COMPILED | ceiling | "
              "COMPILED / ceiling | break-even, new listing [simulated s] | "
              "break-even, cached |", "|---|---|---|---|---|---|---|---|"]
    for name in names:
        case = cases[name]
        model = amilpy.loads(case.text, name=f"{name}.amil")
        fintim = case.fintim * long if "FINISH" not in case.text else case.fintim
        atol = 1e-6 * case.atol_factor()
        reps = max(1, repeats // 2)
        t_auto, run = timed(model, reps, method="AUTO", fintim=fintim, rtol=1e-6, atol=atol)
        t_comp, _ = timed(model, reps, method="COMPILED", fintim=fintim, rtol=1e-6, atol=atol)
        t_ceil = ceiling_long(case, fintim, 1e-6, reps)
        fintim = run.t_end  # (a FINISH ends it sooner)
        saved = (t_auto - t_comp) / fintim
        cold, warm = result["startup"][name]
        # what COMPILED costs before its first step: numba, the kernel, the model
        extra_cold, extra_warm = sum(cold[:3]), sum(warm[:3])
        be = (extra_cold / saved, extra_warm / saved) if saved > 0 else (math.inf, math.inf)
        result["break_even"][name] = (t_auto / fintim, t_comp / fintim, t_ceil / fintim, be)
        lines.append(f"| {name} | {fintim:g} | {t_auto / fintim * 1e3:.3g} | "
                     f"{t_comp / fintim * 1e3:.3g} | {t_ceil / fintim * 1e3:.3g} | "
                     f"{t_comp / t_ceil:.2f} | {be[0]:.3g} | {be[1]:.3g} |")
    text = "\n".join(lines) + "\n"
    print(text)
    if out_dir:
        os.makedirs(out_dir, exist_ok=True)
        with open(os.path.join(out_dir, "compiled.md"), "w") as fh:
            fh.write(text)
    result["markdown"] = text
    return result


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="*")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--long", type=float, default=20.0, help="long runs: FINTIM times this")
    p.add_argument("--out", default=os.path.join(ROOT, "benchmarks", "results"))
    a = p.parse_args()
    main(a.models, a.repeats, a.long, a.out)
