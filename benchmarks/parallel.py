"""Independent runs on 1, 2 and every core: a 200-point grid of the hoist.

    OPENBLAS_NUM_THREADS=1 python benchmarks/parallel.py [--jobs 1 2 4] [--scheduler ADDR]

The grid: W = 60 ... 79 rad/s (20 values) by ZETA = 0.002 ... 0.02 (10 values), one
run of the shipped hoist listing per pair (`amilpy.batch.sweep.sweep` with `grid=`, what
`amilpy sweep hoist_backlash.amil W=60:79:1 ZETA=0.002:0.02:0.002` runs), each
measured as the sweep measures it. Wall time for each number of worker processes,
the speed-up over one, and a check that every point equals the serial one bit for
bit. `--scheduler`: the same grid on a Dask cluster too (`amilpy[cluster]`).
Writes `parallel.md` in `--out` (default `benchmarks/results`).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import ROOT  # noqa: E402

W = [60.0 + k for k in range(20)]
ZETA = [round(0.002 * (k + 1), 6) for k in range(10)]


def main(jobs=None, scheduler: str | None = None, out_dir: str | None = None,
         fintim: float | None = None, w=None, zeta=None) -> dict:
    import amilpy
    from amilpy.batch.farm import default_jobs
    from amilpy.batch.sweep import sweep

    w, zeta = w or W, zeta or ZETA
    cores = default_jobs()
    jobs = jobs or sorted({1, 2, cores})
    model = amilpy.load(os.path.join(ROOT, "models", "hoist_backlash.amil"))
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    rows, reference = [], None
    settings = [(f"{j} process{'es' if j > 1 else ''}", j, None) for j in jobs]
    if scheduler:
        settings.append((f"Dask at {scheduler}", 1, scheduler))
    for label, j, address in settings:
        t0 = time.perf_counter()
        result = sweep(model, "W", w, measure="Y", grid=("ZETA", zeta), jobs=j,
                       scheduler=address, fintim=fintim)
        seconds = time.perf_counter() - t0
        if reference is None:
            reference = result.points
        rows.append({"setting": label, "jobs": j, "seconds": seconds,
                     "same": result.points == reference,
                     "failed": sum(p.status == "failed" for p in result.points)})
        print(f"{label}: {seconds:.2f} s, points equal to the first: {rows[-1]['same']}",
              flush=True)
    base = rows[0]["seconds"]
    load = f"{load} before, {' '.join(f'{x:.2f}' for x in os.getloadavg())} after"
    lines = [f"{len(w) * len(zeta)} hoist runs (W x ZETA grid, FINTIM "
             f"{fintim or 5.0:g} s), {cores} core(s); machine load (`uptime`): {load}", "",
             "| workers | wall time [s] | speed-up | points equal to one process's |",
             "|---|---|---|---|"]
    lines += [f"| {r['setting']} | {r['seconds']:.2f} | {base / r['seconds']:.2f}x | "
              f"{'yes' if r['same'] else 'NO'} |" for r in rows]
    text = "\n".join(lines) + "\n"
    out_dir = out_dir or os.path.join(ROOT, "benchmarks", "results")
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "parallel.md"), "w") as fh:
        fh.write(text)
    print(text)
    return {"rows": rows}


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--jobs", type=int, nargs="*", help="worker counts (default 1, 2, all)")
    p.add_argument("--scheduler", help="also on this Dask scheduler")
    p.add_argument("--fintim", type=float, help="shorter runs (default: the listing's 5 s)")
    p.add_argument("--out", default=None)
    a = p.parse_args()
    main(a.jobs, a.scheduler, a.out, a.fintim)
