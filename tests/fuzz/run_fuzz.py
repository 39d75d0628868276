#!/usr/bin/env python
"""A fuzz campaign by hand: mutations of every shipped and test listing, plus the
hand-made extreme inputs, through `amilpy run` in a memory-limited worker.

    OPENBLAS_NUM_THREADS=1 python tests/fuzz/run_fuzz.py --count 5000 --seed 1

Prints a summary by outcome kind and writes every failing case (listing +
command + detail) to --out (default: fuzz-findings/ in the current directory),
so that it can be replayed with ``amilpy run <file> --quiet``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from fuzz import mutate, target  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=1000, help="number of mutated listings")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=target.DEFAULT_TIMEOUT,
                    help="seconds per case")
    ap.add_argument("--mem", type=int, default=target.DEFAULT_MEM_MB, help="MB per worker")
    ap.add_argument("--extremes", action="store_true", help="also run the hand-made inputs")
    ap.add_argument("--big", action="store_true", help="also run a 50 MB listing")
    ap.add_argument("--cli", type=int, default=0, metavar="N",
                    help="also N command lines with hostile numeric values")
    ap.add_argument("--commands", type=int, default=0, metavar="N",
                    help="also N mutated listings through check, report, sweep, modes, "
                         "periodic, response, montecarlo, sensitivity and steady in turn")
    ap.add_argument("--out", default="fuzz-findings")
    a = ap.parse_args(argv)

    cases = list(mutate.generate(a.count, a.seed))
    if a.cli:
        cases += list(mutate.cli_cases(a.cli, a.seed))
    if a.commands:
        cases += list(mutate.command_cases(a.commands, a.seed))
    if a.extremes:
        cases += [(k, v, f"extreme {k}") for k, v in mutate.extreme_cases().items()]
    if a.big:
        import tempfile

        p = os.path.join(tempfile.mkdtemp(prefix="amilbig-"), "big.amil")
        mutate.big_file(p, 50)
        with open(p, "rb") as fh:
            cases.append(("big_50MB", fh.read(), "50 MB listing"))
    started = time.perf_counter()
    done = [0]

    def progress(r):
        done[0] += 1
        if done[0] % 100 == 0:
            print(f"  {done[0]}/{len(cases)} ({time.perf_counter() - started:.0f} s)",
                  file=sys.stderr)

    results = target.run_cases(cases, timeout=a.timeout, mem_mb=a.mem, progress=progress)
    elapsed = time.perf_counter() - started
    summary = target.summarize(results)
    print(f"{len(results)} inputs in {elapsed:.1f} s; by outcome:")
    for kind, n in summary.items():
        print(f"  {kind:12s} {n}")
    slow = sorted(results, key=lambda r: -r.seconds)[:5]
    print("slowest: " + ", ".join(f"{r.case} {r.seconds:.2f} s" for r in slow))
    bad = [r for r in results if not r.ok]
    if bad:
        os.makedirs(a.out, exist_ok=True)
        data = {c[0]: c[1] for c in cases}
        argvs = {c[0]: c[3] for c in cases if len(c) > 3}
        for r in bad:
            base = os.path.join(a.out, f"{r.kind}-{r.case}")
            with open(base + ".amil", "wb") as fh:
                fh.write(data[r.case])
            argv = argvs.get(r.case, ["run", "{path}", *target.RUN_ARGS])
            command = " ".join(base + ".amil" if x == "{path}" else repr(x) if not x or
                               " " in x else x for x in argv)
            with open(base + ".json", "w") as fh:
                json.dump({**target.as_dict(r), "command": "amilpy " + command}, fh, indent=1)
        print(f"{len(bad)} failing cases written to {a.out}/")
        seen = {}
        for r in bad:
            key = (r.kind, r.detail.strip().splitlines()[-1][:120] if r.detail else "")
            seen.setdefault(key, r.case)
        print("distinct failures (kind, last line of detail, first case):")
        for (kind, last), case in seen.items():
            print(f"  {kind}: {last}  [{case}]")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
