"""Is an optional numba JIT of the generated right-hand side worth an extra?

Run by hand in an environment with numba (`pip install numba`):

    OPENBLAS_NUM_THREADS=1 python benchmarks/jit_probe.py [model.amil]

It compiles the first run's generated `rhs` with `numba.njit` and times one call
and a whole `odeint` integration (the AUTO route's engine) at three tolerances
against the plain-Python function amilpy uses. amilpy's generated code works on
Python floats, so a call costs about as little as numba's dispatcher alone:
measured on the torque-meter model (8 states), 0.55 us (Python) against 1.05 us
(numba) per call, and 5-8 % less time end to end: a compiled right side alone is
not worth a dependency. What the `amilpy[fast]` extra does instead (METHOD
COMPILED) is compile the step loop, the rows and the crossings with it
(`amilpy/compiled`, measured by `compiled.py`).
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy.integrate import odeint  # noqa: E402

import amilpy  # noqa: E402
from amilpy.run import prepare  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def per_call(fn, n: int = 20000) -> float:
    start = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - start) / n * 1e6


def main(path: str | None = None) -> None:
    try:
        import numba
    except ImportError:
        print("numba is not installed: pip install numba")
        return
    path = path or os.path.join(ROOT, "models", "ex4_torque_meter.amil")
    model = amilpy.load(path)
    prepared = prepare(model.ir, model.ir.runs[0])
    compiled = prepared.code
    source = compiled.source.split("def surf")[0]
    # the same function returning an array, for numba (compiler text, not model text)
    head, ret = source.rsplit("return [", 1)
    namespace = {"np": np}
    # the run's parameters (p_NAME globals): numba takes globals as constants
    namespace.update({k: v for k, v in compiled.namespace.items() if k.startswith("p_")})
    exec(head + "return np.array([" + ret.rstrip() + ")", namespace)  # noqa: S102
    start = time.perf_counter()
    jitted = numba.njit(namespace["rhs"])
    n = len(compiled.y0)
    y0 = np.asarray(compiled.y0, dtype=float)
    modes = tuple(1.0 for _ in compiled.watched)
    z0 = tuple(compiled.z0)
    jitted(0.0, y0, modes, z0)
    first = time.perf_counter() - start
    plain = compiled.rhs
    print(f"{os.path.basename(path)}: {n} states; numba's first call (compiling) "
          f"{first * 1e3:.0f} ms")
    print(f"one call: python {per_call(lambda: plain(0.0, y0.tolist(), modes, z0)):.3f} us, "
          f"numba {per_call(lambda: jitted(0.0, y0, modes, z0)):.3f} us")
    fintim = prepared.plan.timer["FINTIM"]
    grid = np.linspace(0.0, fintim, 1001)
    print(f"{'rtol':>8} {'python ms':>10} {'numba ms':>10} {'gain':>6}")
    for rtol in (1e-3, 1e-6, 1e-9):
        times = {}
        for name, f in (("python", lambda t, y: plain(t, y.tolist(), modes, z0)),
                        ("numba", lambda t, y: jitted(t, y, modes, z0))):
            best = np.inf
            for _ in range(5):
                start = time.perf_counter()
                odeint(f, y0, grid, tfirst=True, rtol=rtol, atol=rtol * 1e-3, mxstep=10**6)
                best = min(best, time.perf_counter() - start)
            times[name] = best * 1e3
        gain = 1 - times["numba"] / times["python"]
        print(f"{rtol:8.0e} {times['python']:10.2f} {times['numba']:10.2f} {gain:6.1%}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
