"""Long runs (issue 29): time per simulated second and peak memory against FINTIM.

    OPENBLAS_NUM_THREADS=1 python benchmarks/longrun.py [--models hoist_backlash machine_unit]
        [--fintims 10 100 1000] [--methods AUTO COMPILED] [--rtol R] [--tree PATH]
        [--stream] [--max-events N] [--max-steps N] [--out DIR]

Each point runs in a fresh process (its peak resident memory is its own): the listing
is loaded and run once over its own FINTIM first (imports, code generation, numba's
kernel: the fixed costs), the resident memory is read, then the run at FINTIM is
timed (CPU time). Printed: CPU ms per simulated second, the peak resident memory of
the process, the baseline before the long run (Python, NumPy, SciPy, and numba's
LLVM for COMPILED), and the run's own share (peak - baseline) per row held.

`--tree PATH` runs another checkout's amilpy (a worktree of an older commit) on its
own models, for a before/after table. `--stream` writes the long run's CSV as it
goes (`Model.run(stream_csv=)`, what `amilpy run --csv` does for a long run): the
rows are then the CSV's, and the table goes to longrun_stream.md.

A run that keeps its cost per simulated second and its memory per row whatever its
length is what this checks: before issue 29, AUTO's memory grew with the square of
FINTIM (every restart copied the rest of the output grid, and the rows kept views
of the copies) and COMPILED's kernel allocated a row buffer as long as the rest of
the run at every call. Nothing here asserts a time; `tests/test_longrun.py` guards
the memory with a limit.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

_PROBE = r"""
import json, os, resource, sys, time
import amilpy
path, method, fintim = sys.argv[1], sys.argv[2], float(sys.argv[3])
rtol = float(sys.argv[4]) if sys.argv[4] != "-" else None
max_events, max_steps = (int(x) for x in sys.argv[5].split(","))
stream = sys.argv[6] if len(sys.argv) > 6 else None
m = amilpy.load(path)
kw = dict(method=method, advice=False, rtol=rtol, atol=None if rtol is None else rtol * 1e-3,
          max_events=max_events, max_steps=max_steps)
m.run(**kw)  # the fixed costs: imports, code generation, the kernel
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
start = time.process_time()
run, = m.run(fintim=fintim, stream_csv=stream, **kw)
cpu = time.process_time() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
rows = len(run.t)
if stream:
    with open(stream) as fh:
        rows = sum(1 for _ in fh) - 1
    os.unlink(stream)
print(json.dumps({"cpu": cpu, "base": base, "peak": peak, "rows": rows,
                  "columns": len(run.values), "events": len(run.events),
                  "status": str(run.status), "method": run.method}))
"""


def point(model: str, method: str, fintim: float, rtol: float | None,
          tree: str = ROOT, stream: bool = False, limits: tuple[int, int] = (200_000, 5_000_000)
          ) -> dict:
    import tempfile

    path = os.path.join(tree, "models", f"{model}.amil")
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", PYTHONPATH=tree)
    csv = [os.path.join(tempfile.mkdtemp(), "rows.csv")] if stream else []
    out = subprocess.run([sys.executable, "-c", _PROBE, path, method, repr(fintim),
                          repr(rtol) if rtol else "-", ",".join(map(str, limits)), *csv],
                         capture_output=True, text=True, cwd=tree, env=env)
    if out.returncode:
        return {"model": model, "method": method, "fintim": fintim,
                "error": out.stderr.strip().splitlines()[-1] if out.stderr else "failed"}
    r = json.loads(out.stdout.strip().splitlines()[-1])
    r["ran"] = r.pop("method")
    r.update(model=model, method=method, fintim=fintim,
             ms_per_s=1e3 * r["cpu"] / fintim,
             bytes_per_row=(r["peak"] - r["base"]) * 2**20 / max(r["rows"], 1))
    return r


def table(rows: list[dict]) -> str:
    lines = ["| model | method (as run) | FINTIM [s] | CPU [s] | ms per simulated s "
             "| peak RSS [MB] | before the run [MB] | run's own [MB] | rows | bytes per row "
             "(row: columns x 8) | events | status |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['model']} | {r['method']} | {r['fintim']:g} | "
                         f"{r['error']} ||||||||")
            continue
        lines.append(
            f"| {r['model']} | {r['method']} ({r['ran']}) | {r['fintim']:g} | "
            f"{r['cpu']:.2f} | {r['ms_per_s']:.2f} | "
            f"{r['peak']:.0f} | {r['base']:.0f} | {r['peak'] - r['base']:.0f} | "
            f"{r['rows']} | {r['bytes_per_row']:.0f} ({8 * (r['columns'] + 2)}) | "
            f"{r['events']} | {r['status']} |")
    return "\n".join(lines)


def main(models=("hoist_backlash", "machine_unit"), fintims=(10.0, 100.0, 1000.0),
         methods=("AUTO", "COMPILED"), rtol: float | None = None,
         out_dir: str | None = None, tree: str = ROOT, stream: bool = False,
         limits: tuple[int, int] = (200_000, 5_000_000)) -> list[dict]:
    rows = []
    for model in models:
        for method in methods:
            for fintim in fintims:
                r = point(model, method, fintim, rtol, tree, stream, limits)
                rows.append(r)
                print(table([r]).splitlines()[-1], flush=True)
    text = table(rows)
    print()
    print(text)
    if out_dir:
        os.makedirs(out_dir, exist_ok=True)
        name = "longrun_stream.md" if stream else "longrun.md"
        with open(os.path.join(out_dir, name), "w", encoding="utf-8") as f:
            f.write(text + "\n")
    return rows


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", nargs="+", default=["hoist_backlash", "machine_unit"])
    ap.add_argument("--fintims", nargs="+", type=float, default=[10.0, 100.0, 1000.0])
    ap.add_argument("--methods", nargs="+", default=["AUTO", "COMPILED"])
    ap.add_argument("--rtol", type=float, default=None,
                    help="RELERR (ABSERR = RELERR x 1e-3); default: the listing's own")
    ap.add_argument("--tree", default=ROOT, help="the checkout whose amilpy runs")
    ap.add_argument("--stream", action="store_true",
                    help="stream the long run's CSV as it goes (Model.run(stream_csv=))")
    ap.add_argument("--max-events", type=int, default=200_000,
                    help="the runs' event limit (the hoist switches 45 times a second: "
                         "450,000 times in 10,000 s)")
    ap.add_argument("--max-steps", type=int, default=5_000_000,
                    help="the runs' step limit (the hoist takes 770 steps a second)")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    main(a.models, a.fintims, a.methods, a.rtol, a.out, os.path.abspath(a.tree), a.stream,
         (a.max_events, a.max_steps))
