"""Whole-process start-up cost of the CLI, and what it imports.

    OPENBLAS_NUM_THREADS=1 python benchmarks/startup.py [--repeats 10] [--model FILE]

Times (median of ``--repeats`` subprocesses, wall clock) of

* ``python -c pass`` (the interpreter alone) and ``python -c "import scipy.integrate"``;
* ``amilpy check MODEL`` and ``amilpy run --quiet MODEL`` (MODEL: a small shipped model,
  ``models/crank_slider_startup.amil`` by default), run as ``python -c 'from amilpy.cli
  import main; main()'`` so that no launcher (a pyenv shim, a console-script wrapper)
  is counted; the console script itself is timed too, for reference;

and, from ``python -X importtime``, whether ``check`` imports SciPy and whether ``run``
without ``--plot`` imports matplotlib, with the summed import time of ``amilpy``,
``lark``, ``numpy``, ``scipy`` and ``matplotlib`` in each. Targets (issue 4): check under
0.25 s; run within 0.3 s of the bare SciPy import. Writes ``startup.md`` / ``startup.csv``.
"""

from __future__ import annotations

import argparse
import csv
import os
import shutil
import statistics
import subprocess
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import ROOT  # noqa: E402

CLI = "import sys; from amilpy.cli import main; sys.argv[0] = 'amilpy'; sys.exit(main())"


def _time(cmd: list[str], repeats: int) -> tuple[float, int]:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    times, rc = [], 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                           cwd=ROOT)
        times.append(time.perf_counter() - t0)
        rc = p.returncode
    return statistics.median(times), rc


def importtime(args: list[str]) -> dict[str, float]:
    """Top-level package -> summed *self* import time [s] of all its modules, from
    ``python -X importtime`` (self times add up; cumulative ones nest)."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    p = subprocess.run([sys.executable, "-X", "importtime", "-c", CLI, *args],
                       capture_output=True, text=True, env=env, cwd=ROOT)
    tot: dict[str, float] = {}
    for line in p.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        parts = line.split("|")
        try:
            self_us = int(parts[0].split(":")[1])
        except ValueError:
            continue
        top = parts[2].strip().split(".")[0]
        tot[top] = tot.get(top, 0.0) + self_us * 1e-6
    return tot


def main(repeats: int = 10, model: str | None = None, out_dir: str | None = None) -> dict:
    model = model or os.path.join(ROOT, "models", "crank_slider_startup.amil")
    py = sys.executable
    rows = []
    cmds = [
        ("python -c pass", [py, "-c", "pass"]),
        ("python -c 'import scipy.integrate'", [py, "-c", "import scipy.integrate"]),
        ("python -c 'import numpy'", [py, "-c", "import numpy"]),
        ("amilpy check", [py, "-c", CLI, "check", model]),
        ("amilpy run --quiet", [py, "-c", CLI, "run", "--quiet", model]),
    ]
    script = shutil.which("amilpy")
    if script:
        cmds.append(("amilpy check (console script on PATH)", [script, "check", model]))
    for label, cmd in cmds:
        secs, rc = _time(cmd, repeats)
        rows.append({"what": label, "median_s": secs, "rc": rc})
        print(f"{label:<42} {secs * 1e3:8.1f} ms  rc={rc}", flush=True)
    t = {r["what"]: r["median_s"] for r in rows}
    check_s = t["amilpy check"]
    run_s = t["amilpy run --quiet"]
    scipy_s = t["python -c 'import scipy.integrate'"]
    imp_check = importtime(["check", model])
    imp_run = importtime(["run", "--quiet", model])
    findings = {
        "check_s": check_s, "run_s": run_s, "scipy_import_s": scipy_s,
        "run_minus_scipy_s": run_s - scipy_s,
        "check_target_met": check_s < 0.25, "run_target_met": run_s - scipy_s < 0.3,
        "check_imports_scipy": "scipy" in imp_check,
        "check_imports_matplotlib": "matplotlib" in imp_check,
        "run_imports_matplotlib": "matplotlib" in imp_run,
        "imports_check": imp_check, "imports_run": imp_run,
    }
    lines = [f"Model: `{os.path.relpath(model, ROOT)}`; median of {repeats} processes.", "",
             "| command | median wall time [ms] |", "|---|---|"]
    lines += [f"| `{r['what']}` | {r['median_s'] * 1e3:.1f} |" for r in rows]
    lines += ["",
              f"* `amilpy check`: {check_s * 1e3:.0f} ms (target < 250 ms: "
              f"{'met' if findings['check_target_met'] else 'MISSED'})",
              f"* `amilpy run --quiet` − `import scipy.integrate`: "
              f"{(run_s - scipy_s) * 1e3:.0f} ms (target < 300 ms: "
              f"{'met' if findings['run_target_met'] else 'MISSED'})",
              f"* `check` imports SciPy: {findings['check_imports_scipy']}; matplotlib: "
              f"{findings['check_imports_matplotlib']}",
              f"* `run` (no --plot) imports matplotlib: {findings['run_imports_matplotlib']}",
              "", "Import time by top-level package (`python -X importtime`, sum of self "
              "times of its modules) [ms]:",
              "", "| package | check | run --quiet |", "|---|---|---|"]
    for pkg in ("amilpy", "lark", "numpy", "scipy", "matplotlib"):
        a, b = imp_check.get(pkg), imp_run.get(pkg)
        lines.append(f"| {pkg} | {'-' if a is None else f'{a * 1e3:.1f}'} | "
                     f"{'-' if b is None else f'{b * 1e3:.1f}'} |")
    md = "\n".join(lines) + "\n"
    out_dir = out_dir or os.path.join(ROOT, "benchmarks", "results")
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "startup.md"), "w") as fh:
        fh.write(md)
    with open(os.path.join(out_dir, "startup.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, ["what", "median_s", "rc"])
        w.writeheader()
        w.writerows(rows)
    print(md)
    return {"rows": rows, **findings}


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=10)
    p.add_argument("--model", default=None)
    p.add_argument("--out", default=None)
    a = p.parse_args()
    main(a.repeats, a.model, a.out)
