"""Memory of a large model (issue 29 point 3): the N-mass chain of `scale.py`, read,
run once (code generation and the Jacobian included) and run again, each N in a
fresh process.

    OPENBLAS_NUM_THREADS=1 python benchmarks/largemem.py [--sizes 1000 10000]

Printed per N: the wall time and the process's peak and held resident memory after
each phase (peak: `getrusage`; held: the resident set from /proc/self/statm), and the
run's state history (states x rows x 8 bytes), the yardstick the issue names. A
second run's growth is what a run itself costs; the first run's also holds the
generated code, built on first use.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))

_PROBE = r"""
import json, resource, sys, time
sys.path.insert(0, sys.argv[2])
from scale import chain_listing
import amilpy

def peak():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

def held():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2**20

out = {}
text = chain_listing(int(sys.argv[1]))
t0 = time.perf_counter(); m = amilpy.loads(text, "chain")
out["read"] = (time.perf_counter() - t0, peak(), held())
t0 = time.perf_counter(); r, = m.run(advice=False)
out["run1"] = (time.perf_counter() - t0, peak(), held())
t0 = time.perf_counter(); r, = m.run(advice=False)
out["run2"] = (time.perf_counter() - t0, peak(), held())
out["history"] = len(m.ir.states) * len(r.t) * 8 / 2**20
print(json.dumps(out))
"""


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000])
    args = p.parse_args(argv)
    print("| N | read: s, peak, held MB | run 1: s, peak, held MB | run 2: s, peak, held MB "
          "| state history MB |")
    print("|---:|---|---|---|---:|")
    for n in args.sizes:
        got = subprocess.run([sys.executable, "-c", _PROBE, str(n), HERE], check=True,
                             capture_output=True, text=True)
        row = json.loads(got.stdout.strip().splitlines()[-1])
        cells = [f"{row[k][0]:.1f} s, {row[k][1]:.0f}, {row[k][2]:.0f}" for k in
                 ("read", "run1", "run2")]
        print(f"| {n:,} | " + " | ".join(cells) + f" | {row['history']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
