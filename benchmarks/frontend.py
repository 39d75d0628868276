"""The front end's cost per statement: parse, check and code generation of the N-mass
chain (`scale.chain_listing`), and of the shipped models, against another checkout.

    OPENBLAS_NUM_THREADS=1 python benchmarks/frontend.py                    # this tree
    python benchmarks/frontend.py --before /path/to/worktree --repeats 5

Each point is measured in a fresh process (nothing cached from an earlier listing,
the garbage collector as a user's process has it; a two-mass chain read first, so
lark's tables and the lazy imports are not counted), the checkouts taking turns
round by round; the table gives the median over the rounds of each stage's CPU
time divided by the number of statements. `--before` is a worktree of an older
commit (`git worktree add /tmp/before COMMIT`) or an export of it (`git archive COMMIT
| tar -x -C /tmp/before`); its amilpy runs from there (but with an editable install,
`amilpy.grammar` comes from where the install points, for both checkouts).
Writes `frontend.md` in `--out` (default `benchmarks/results`).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cases import ROOT  # noqa: E402

# one point, run in a fresh process with PYTHONPATH at the checkout: argv = (the
# benchmarks folder, N or a model's path); prints the stages' seconds as JSON
_PROBE = r"""
import json, sys, time
from amilpy.check import check  # (first: the checkout's, before the benchmarks' path
from amilpy.parse import parse  # puts this tree's first)
from amilpy.run import prepare
sys.path.insert(0, sys.argv[1])
from scale import chain_listing

what = sys.argv[2]
if what.isdigit():
    n = int(what)
    text, name, statements = chain_listing(n), "chain", 3 * n - 1
else:
    text, name, statements = open(what).read(), what, None
warm = check(parse(chain_listing(2), "warm"), "warm")  # (lark's tables, lazy imports:
prepare(warm, warm.runs[0])                            # once per process, not per listing)
t0 = time.process_time()
program = parse(text, name)
t1 = time.process_time()
model = check(program, name)
t2 = time.process_time()
prepare(model, model.runs[0])
t3 = time.process_time()
if statements is None:
    statements = len(model.dynamic) + len(model.states) + len(model.initial)
import amilpy
assert amilpy.__file__.startswith(sys.argv[3]), (amilpy.__file__, sys.argv[3])
print(json.dumps({"statements": statements, "parse": t1 - t0, "check": t2 - t1,
                  "codegen": t3 - t2}))
"""

SIZES = (10, 100, 1000, 3000)
MODELS = ("ex4_clutch", "hoist_backlash", "machine_unit")


def point(tree: str, what: str) -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", PYTHONPATH=tree)
    out = subprocess.run([sys.executable, "-c", _PROBE, os.path.dirname(os.path.abspath(
        __file__)), what, tree], capture_output=True, text=True, check=True, cwd=tree, env=env)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(sizes=SIZES, models=MODELS, repeats: int = 3, before: str | None = None,
         out_dir: str | None = None) -> list[dict]:
    trees = {"now": ROOT} | ({"before": before} if before else {})
    cases = [str(n) for n in sizes] + [os.path.join("models", f"{m}.amil") for m in models]
    got: dict[tuple[str, str], list[dict]] = {}
    for _ in range(repeats):
        for case in cases:
            for label, tree in trees.items():
                what = case if case.isdigit() else os.path.join(tree, case)
                got.setdefault((label, case), []).append(point(tree, what))
    rows = []
    for case in cases:
        row = {"case": f"chain N = {case}" if case.isdigit() else os.path.basename(case)}
        for label in trees:
            points = got[(label, case)]
            row["statements"] = points[0]["statements"]
            for stage in ("parse", "check", "codegen"):
                row[f"{label}_{stage}"] = statistics.median(
                    p[stage] / p["statements"] * 1e6 for p in points)
            row[f"{label}_total"] = sum(row[f"{label}_{s}"] for s in ("parse", "check",
                                                                      "codegen"))
        rows.append(row)
    text = markdown(rows, list(trees), repeats, before)
    out_dir = out_dir or os.path.join(ROOT, "benchmarks", "results")
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "frontend.md"), "w") as fh:
        fh.write(text)
    print(text)
    return rows


def markdown(rows: list[dict], labels: list[str], repeats: int, before: str | None) -> str:
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    head = ["case", "statements"]
    for label in labels:
        head += [f"{label}: parse", "check", "codegen", "total"]
    if len(labels) == 2:
        head.append("before / now")
    lines = ["# The front end per statement [us]", "",
             f"`python benchmarks/frontend.py --repeats {repeats}"
             + (f" --before {before}`" if before else "`")
             + f"; median of {repeats} fresh processes per point; load average {load} "
             "at the end.", "", "| " + " | ".join(head) + " |",
             "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["case"], str(r["statements"])]
        for label in labels:
            cells += [f"{r[f'{label}_{s}']:.0f}" for s in ("parse", "check", "codegen",
                                                            "total")]
        if len(labels) == 2:
            cells.append(f"{r['before_total'] / r['now_total']:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="*", default=list(SIZES))
    p.add_argument("--models", nargs="*", default=list(MODELS))
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--before", default=None, help="another checkout, run side by side")
    p.add_argument("--out", default=None)
    a = p.parse_args()
    main(a.sizes, a.models, a.repeats, os.path.abspath(a.before) if a.before else None,
         a.out)
