""""Skip what a run does not need": each effect measured.

    OPENBLAS_NUM_THREADS=1 python benchmarks/skip_effects.py [--repeats 5]

(a) Equations that feed neither a state nor a requested output are not evaluated: a
    two-state oscillator with N_ALG algebraic outputs; ``Model.run(outputs=["X"])`` against
    ``outputs=None``, and the generated ``rhs``/``out`` sources (line counts, names).
(b) Outputs are computed only at output instants: the compiled ``out`` is wrapped in a
    counter; its calls against ``nfev`` and the number of output rows.
(c) Switches that cannot change branch are not watched and switches on TIME are
    breakpoints: ``FSW`` of a constant and ``STEP(T1)`` against the same switches
    written on states (a constant state and a clock state); watched surfaces, events,
    steps, nfev, time and error against the closed form.
(d) Parameters by name, constants folded: a snippet of the generated ``rhs`` of
    ``ex4_clutch`` next to its listing lines; the time of that ``rhs`` against the same
    source with every parameter's value folded in, and the time to prepare a run with a
    new PARAM value (the code bound again) against one that compiles.

Writes ``skip_effects.md`` in ``--out`` (default ``benchmarks/results``).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import statistics
import sys
import time
import timeit

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import ROOT  # noqa: E402

N_ALG = 40


def many_outputs_listing(n: int = N_ALG) -> str:
    lines = ["TITLE OSCILLATOR WITH MANY ALGEBRAIC OUTPUTS", "PARAM W = 6.283185307179586",
             "DYNAMIC", "   X = INTGRL(1.0, V)", "   V = INTGRL(0.0, -W**2*X)"]
    prev = "X"
    for k in range(n):
        lines.append(f"   A{k} = SIN({prev} + {k + 1}.0*V) + EXP(-ABS({prev}))")
        prev = f"A{k}"
    lines += ["TIMER FINTIM = 10.0, OUTDEL = 0.01", "END"]
    return "\n".join(lines) + "\n"


SWITCH_TIME = """TITLE CONSTANT AND TIME SWITCHES
PARAM A = 1.0, T1 = 0.5
DYNAMIC
   S1 = FSW(A, -1.0, 0.0, 1.0)
   S2 = STEP(T1)
   X  = INTGRL(0.0, S1 + S2 - X)
TIMER FINTIM = 2.0, OUTDEL = 0.01
END
"""

SWITCH_STATE = """TITLE THE SAME SWITCHES WRITTEN ON STATES
PARAM A = 1.0, T1 = 0.5
DYNAMIC
   AS = INTGRL(A, 0.0)
   TT = INTGRL(0.0, 1.0)
   S1 = FSW(AS, -1.0, 0.0, 1.0)
   S2 = FSW(TT - T1, 0.0, 1.0, 1.0)
   X  = INTGRL(0.0, S1 + S2 - X)
TIMER FINTIM = 2.0, OUTDEL = 0.01
END
"""


def _switch_exact(t):
    x1 = 1.0 - math.exp(-0.5)
    return np.where(t < 0.5, 1.0 - np.exp(-t), 2.0 - (2.0 - x1) * np.exp(-(t - 0.5)))


def _median(fn, repeats):
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def _fn_source(src: str, name: str) -> str:
    m = re.search(rf"^def {name}\(.*?(?=^def |\Z)", src, re.S | re.M)
    return m.group(0) if m else ""


def effect_a(repeats: int) -> tuple[list[str], dict]:
    import amilpy
    from amilpy.run import Options, prepare

    m = amilpy.loads(many_outputs_listing(), "many_outputs")
    m.run()
    m.run(outputs=["X"])
    res = {}
    for method in ("AUTO", "RKS"):
        t_all = _median(lambda method=method: m.run(method=method), repeats)
        t_few = _median(lambda method=method: m.run(method=method, outputs=["X"]),
                        repeats)
        res[method] = (t_all, t_few)
    src = m.python_source()
    rhs, out = _fn_source(src, "rhs"), _fn_source(src, "out")
    few = prepare(m.ir, m.ir.runs[0], Options(outputs=["X"])).code
    out_few = _fn_source(few.source, "out")
    lines = [f"### (a) unneeded equations: oscillator + {N_ALG} algebraic outputs "
             "(A0 .. A{N-1}, each SIN/EXP of the previous)", "",
             f"* generated `rhs`: {len(rhs.splitlines())} lines, mentions an algebraic output: "
             f"{'yes' if re.search(r'v_A[0-9]', rhs) else 'no'}",
             f"* generated `out` (all outputs): {len(out.splitlines())} lines; with "
             f"`outputs=['X']`: {len(out_few.splitlines())} lines",
             "", "| method | outputs=None [ms] | outputs=['X'] [ms] | saving |",
             "|---|---|---|---|"]
    for method, (a, b) in res.items():
        lines.append(f"| {method} | {a * 1e3:.2f} | {b * 1e3:.2f} | {(1 - b / a) * 100:.0f}% |")
    lines += ["", "```python", rhs.strip(), "```", ""]
    return lines, res


def effect_b() -> tuple[list[str], list]:
    import amilpy
    from amilpy.run import prepare

    rows = []
    for path in ("models/machine_unit.amil", "models/ex4_clutch.amil"):
        m = amilpy.load(os.path.join(ROOT, path))
        m.run()
        for method in ("AUTO", "RKS", "RADAU"):
            calls = [0]
            for c in [prepare(m.ir, spec, cache=m.cache).code for spec in m.ir.runs]:
                if not getattr(c.out, "_counted", False):
                    orig = c.out

                    def counted(*a, _o=orig, calls=calls):
                        calls[0] += 1
                        return _o(*a)

                    counted._counted = True
                    c.out = counted
            calls[0] = 0
            try:
                r = m.run(method=method)[0]
                rows.append((os.path.basename(path), method, r.stats["nfev"], calls[0],
                             len(r.t), len(r.events), ""))
            except Exception as exc:  # noqa: BLE001
                rows.append((os.path.basename(path), method, None, calls[0], None, None,
                             f"ERROR {type(exc).__name__}"))
    lines = ["### (b) outputs only at output instants (calls of the compiled `out`)", "",
             "| model | method | RHS evaluations | out() calls | output rows | events | |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| " + " | ".join("" if x is None else str(x) for x in r) + " |")
    return lines + [""], rows


def effect_c(repeats: int) -> tuple[list[str], list]:
    import amilpy
    from amilpy.run import prepare

    rows = []
    for label, text in (("FSW(const) + STEP(T1)", SWITCH_TIME),
                        ("same on states", SWITCH_STATE)):
        m = amilpy.loads(text, label)
        prepared = prepare(m.ir, m.ir.runs[0])
        for method in ("AUTO", "RKS"):
            r = m.run(method=method, rtol=1e-8, atol=1e-10)[0]
            t = _median(lambda m=m, method=method: m.run(method=method, rtol=1e-8, atol=1e-10),
                        repeats)
            err = float(np.max(np.abs(r["X"] - _switch_exact(r.t))))
            kinds = sorted({e.kind for e in r.events})
            rows.append((label, method, len(m.ir.surfaces), len(prepared.code.watched),
                         sum(w.breakpoint_only for w in prepared.plan.watched), len(r.events),
                         ",".join(kinds),
                         r.stats["nsteps"], r.stats["nfev"], t * 1e3, err))
    lines = ["### (c) switches that cannot change branch / switches on TIME", "",
             "| listing | method | surfaces | watched | of them breakpoints | events | event kinds "
             "| steps | nfev | time [ms] | max error |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| " + " | ".join(f"{x:.3g}" if isinstance(x, float) else str(x)
                                       for x in r) + " |")
    return lines + [""], rows


def effect_d() -> tuple[list[str], dict]:
    """Parameters read by name, true constants folded: the cost per call against
    every value folded, and the compilation a new PARAM value no longer pays."""
    import time

    import amilpy
    from amilpy import codegen
    from amilpy.run import Cache, prepare

    m = amilpy.load(os.path.join(ROOT, "models", "ex4_clutch.amil"))
    compiled = prepare(m.ir, m.ir.runs[0]).code
    rhs_src = _fn_source(compiled.source, "rhs")
    params = {k: v for k, v in compiled.namespace.items() if k.startswith("p_")}
    # the same function with every parameter's value folded in, as builds before did
    folded_src = re.sub(r"\bp_\w+", lambda mo: repr(params[mo.group(0)]), rhs_src)
    ns_p = dict(codegen.NAMESPACE)
    ns_p.update(params)
    exec(compile(rhs_src, "<parameters>", "exec"), ns_p)
    ns_f = dict(codegen.NAMESPACE)
    exec(compile(folded_src, "<folded>", "exec"), ns_f)
    y = [0.3, 1e-3, 500.0, 499.0]
    modes = [1.0] * len(compiled.watched)
    z = list(compiled.z0)
    n = 100000
    tf = min(timeit.repeat(lambda: ns_f["rhs"](0.1, y, modes, z), number=n, repeat=5)) / n
    tp = min(timeit.repeat(lambda: ns_p["rhs"](0.1, y, modes, z), number=n, repeat=5)) / n
    cache = Cache()
    t0 = time.perf_counter()
    prepare(m.ir, m._specs({})[0], None, cache)
    t1 = time.perf_counter()
    prepare(m.ir, m._specs({"C": 2.5})[0], None, cache)  # C: a PARAM
    t2 = time.perf_counter()
    listing = [ln for ln in open(os.path.join(ROOT, "models", "ex4_clutch.amil"))
               if re.match(r"\s+(KE|MOBC|J1|JOBC|T1|TAUM|IA|W1|W2)\s*=", ln)]
    lines = ["### (d) parameters by name, constants folded (ex4_clutch)", "", "Listing:", "",
             "```", *[ln.rstrip() for ln in listing], "```", "", "Generated `rhs`:", "",
             "```python", rhs_src.strip(), "```", "",
             f"CONST values and INITIAL values computed from them alone are folded "
             f"(`KE = KEN*30/PI` became `{compiled.constants.get('KE', float('nan'))!r}`); "
             f"PARAM and INCON values and what INITIAL computes from them are read by name "
             f"({', '.join(sorted(params))}), so a run with other values binds the same "
             "code.", "",
             f"Time of one `rhs` call: parameters by name {tp * 1e6:.3f} µs, every value "
             f"folded {tf * 1e6:.3f} µs ({(tp / tf - 1) * 100:+.0f}%). Preparing a run: "
             f"{(t1 - t0) * 1e3:.1f} ms with compilation, {(t2 - t1) * 1e3:.1f} ms for a new "
             "PARAM value (the code bound again, not compiled).", ""]
    return lines, {"folded_us": tf * 1e6, "globals_us": tp * 1e6,
                   "compile_ms": (t1 - t0) * 1e3, "rebind_ms": (t2 - t1) * 1e3}


def main(repeats: int = 5, out_dir: str | None = None) -> dict:
    out_dir = out_dir or os.path.join(ROOT, "benchmarks", "results")
    la, ra = effect_a(repeats)
    lb, rb = effect_b()
    lc, rc = effect_c(repeats)
    ld, rd = effect_d()
    md = "\n".join(la + lb + lc + ld) + "\n"
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "skip_effects.md"), "w") as fh:
        fh.write(md)
    print(md)
    return {"a": ra, "b": rb, "c": rc, "d": rd}


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--out", default=None)
    a = p.parse_args()
    main(a.repeats, a.out)
