"""The fuzz target: run listings through `amilpy.cli.main` in a worker process.

The worker runs under a memory limit (RLIMIT_AS) and gives each case a
wall-clock budget (SIGALRM); the parent also watches it and kills it if a case
does not come back (a hang in C code). Each case is a file in a fresh
directory, run as ``amilpy run case.amil --quiet --max-time ... --max-steps ...``.

A case passes when the exit code is 0, 1 or 3, no Python traceback is printed,
a failing exit code comes with a message on stderr, and nothing but the
listing (and the CSV a PREPARE statement asks for) appears in its directory.

Usage by the parent: ``run_cases([(case_id, data_bytes, description), ...])``.
"""

from __future__ import annotations

import io
import json
import os
import selectors
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import asdict, dataclass

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

DEFAULT_TIMEOUT = 10.0  # seconds per case, parsing included
DEFAULT_MEM_MB = 2048  # address-space limit of the worker
RUN_ARGS = ["--quiet", "--max-time", "3", "--max-steps", "200000", "--max-events", "20000"]

# modules whose import by a listing would mean foreign code ran
FORBIDDEN_MODULES = {"subprocess", "socket", "shutil", "ctypes", "pty", "webbrowser",
                     "http", "urllib", "ftplib", "smtplib", "telnetlib", "pickle", "marshal"}


@dataclass
class Result:
    case: str
    kind: str  # ok-0, ok-1, ok-3, traceback, exit-N, no-message, hang, died, files, module
    code: int | None
    seconds: float
    detail: str = ""
    description: str = ""

    @property
    def ok(self) -> bool:
        return self.kind.startswith("ok")


class CaseTimeout(BaseException):
    """Raised by SIGALRM inside a case: not an Exception, so nothing swallows it."""


def _alarm(signum, frame):
    raise CaseTimeout()


def run_one(path: str, timeout: float, args: list[str] | None = None) -> dict:
    """Run one listing file through the CLI in this process; classify the outcome.
    A case with its own command line (`case.argv.json` beside it, '{path}' standing
    for the listing) may also end in a usage error (exit 2) and write files."""
    from amilpy.cli import main

    argv_file = os.path.join(os.path.dirname(path), "case.argv.json")
    own_argv = None
    if os.path.exists(argv_file):
        with open(argv_file) as fh:
            own_argv = [path if a == "{path}" else a for a in json.load(fh)]
    accepted = (0, 1, 2, 3) if own_argv else (0, 1, 3)

    folder = os.path.dirname(path)
    stem = os.path.splitext(os.path.basename(path))[0]
    before_files = set(os.listdir(folder))
    before_modules = set(sys.modules)
    out, err = io.StringIO(), io.StringIO()
    code, kind, detail = None, None, ""
    cwd = os.getcwd()
    os.chdir(folder)  # a stray relative write would land here, where it is seen
    started = time.perf_counter()
    signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with redirect_stdout(out), redirect_stderr(err):
            code = main(own_argv or ["run", path, *(args if args is not None else RUN_ARGS)])
    except CaseTimeout:
        kind, detail = "hang", f"no answer within {timeout:g} s"
    except BaseException as exc:  # noqa: BLE001 - anything escaping main is a crash
        kind = "traceback"
        detail = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))[-3000:]
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        os.chdir(cwd)
    seconds = time.perf_counter() - started
    stderr = err.getvalue()
    if kind is None:
        if "Traceback (most recent call last)" in stderr:
            kind, detail = "traceback", stderr[-3000:]
        elif code not in accepted:
            kind, detail = f"exit-{code}", stderr[-1000:]
        elif code != 0 and not stderr.strip():
            kind = "no-message"
        else:
            kind = f"ok-{code}"
            detail = stderr.strip().splitlines()[0][:300] if stderr.strip() else ""
    created = set(os.listdir(folder)) - before_files - {f"{stem}.csv"}
    if created and kind.startswith("ok") and not own_argv:
        kind, detail = "files", f"created {sorted(created)}"
    new = {m.split(".")[0] for m in set(sys.modules) - before_modules}
    if new & FORBIDDEN_MODULES and kind.startswith("ok"):
        kind, detail = "module", f"imported {sorted(new & FORBIDDEN_MODULES)}"
    return {"kind": kind, "code": code, "seconds": seconds, "detail": detail}


def _limit_memory(mem_mb: int) -> None:
    import resource

    limit = mem_mb * 1024 * 1024
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


WARM_UP = b"""TITLE WARM-UP: EVERY LAZY IMPORT HAPPENS HERE, NOT IN A CASE
PARAM K = (1.0, 2.0)
INITIAL
  A = 2.0*K
DYNAMIC
  X = INTGRL(1.0, V)
  V = INTGRL(0.0, -A*X - FSW(V, -0.1, 0.0, 0.1) + STEP(0.5))
  Y = AFGEN(F, X) + QNTZR(0.1, X) + LIMIT(-1.0, 1.0, X) + DEADSP(-0.1, 0.1, X)
FUNCTION F = 0.0, 0.0, 1.0, 1.0
TIMER FINTIM = 1.0, OUTDEL = 0.1
PRINT X, Y
PREPARE X
RANGE X
END
"""


def _warm_up(timeout: float) -> None:
    """Run a model with most features once, for every method, so that lazy
    imports of numpy/scipy/amilpy are done before the first case is watched."""
    from amilpy.cli import main

    d = tempfile.mkdtemp(prefix="amilwarm-")
    try:
        p = os.path.join(d, "warm.amil")
        with open(p, "wb") as fh:
            fh.write(WARM_UP)
        for method in ("AUTO", "RKS", "DOP853", "LSODA", "RADAU", "BDF", "RK4", "EULER",
                       "TRAPZ", "ADAMS"):
            for argv in (["run", p, "--method", method, *RUN_ARGS],
                         ["run", p + ".missing", *RUN_ARGS], ["run", p, "--bad-option"]):
                try:
                    with redirect_stdout(io.StringIO()), redirect_stderr(io.StringIO()):
                        main(argv)
                except Exception:  # noqa: BLE001 - a crash here is found again by a case
                    pass
    finally:
        shutil.rmtree(d, ignore_errors=True)


def worker(list_file: str, timeout: float, mem_mb: int, args: list[str] | None) -> None:
    """Run the cases named in `list_file`; one JSON line per case on the saved stdout."""
    _limit_memory(mem_mb)
    os.environ.setdefault("MPLBACKEND", "Agg")
    proto = os.fdopen(os.dup(1), "w", buffering=1)
    _warm_up(timeout)

    with open(list_file) as fh:
        paths = [line.rstrip("\n") for line in fh if line.strip()]
    for path in paths:
        proto.write(json.dumps({"begin": path}) + "\n")
        res = run_one(path, timeout, args)
        res["path"] = path
        proto.write(json.dumps(res) + "\n")


def run_cases(cases, timeout: float = DEFAULT_TIMEOUT, mem_mb: int = DEFAULT_MEM_MB,
              args: list[str] | None = None, workdir: str | None = None,
              progress=None) -> list[Result]:
    """Run (case_id, bytes, description[, argv]) cases in a worker subprocess.

    Each case gets its own directory. If the worker stops answering (a hang the
    alarm cannot interrupt) or dies (memory limit, a signal), the case in
    progress is recorded as such and a fresh worker takes the remaining cases.
    """
    own = workdir is None
    workdir = workdir or tempfile.mkdtemp(prefix="amilfuzz-")
    paths, meta = [], {}
    for i, (case_id, data, desc, *argv) in enumerate(cases):
        d = os.path.join(workdir, f"{i:06d}")
        os.makedirs(d, exist_ok=True)
        p = os.path.join(d, "case.amil")
        with open(p, "wb") as fh:
            fh.write(data)
        if argv:
            with open(os.path.join(d, "case.argv.json"), "w") as fh:
                json.dump(argv[0], fh)
        paths.append(p)
        meta[p] = (case_id, desc)
    results: dict[str, Result] = {}
    todo = list(paths)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg",
               PYTHONPATH=os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")]))
    try:
        while todo:
            list_file = os.path.join(workdir, "todo.txt")
            with open(list_file, "w") as fh:
                fh.write("\n".join(todo) + "\n")
            cmd = [sys.executable, os.path.abspath(__file__), "--worker", list_file,
                   "--timeout", str(timeout), "--mem", str(mem_mb)]
            if args is not None:
                cmd += ["--args", json.dumps(args)]
            proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                    env=env, text=True)
            sel = selectors.DefaultSelector()
            sel.register(proc.stdout, selectors.EVENT_READ)
            current, began = None, time.perf_counter()
            startup = 60.0  # importing numpy/scipy on a busy machine
            while True:
                budget = (timeout + 20.0) if current else startup
                ready = sel.select(timeout=max(0.1, budget - (time.perf_counter() - began)))
                if not ready:
                    if time.perf_counter() - began < budget:
                        continue
                    proc.kill()
                    proc.wait()
                    if current:
                        results[current] = Result(meta[current][0], "hang", None,
                                                  time.perf_counter() - began,
                                                  "the worker stopped answering; killed",
                                                  meta[current][1])
                    break
                line = proc.stdout.readline()
                if not line:  # the worker is gone
                    proc.wait()
                    if current:
                        err = proc.stderr.read()[-2000:]
                        results[current] = Result(
                            meta[current][0], "died", proc.returncode,
                            time.perf_counter() - began,
                            f"worker exit {proc.returncode}: {err}", meta[current][1])
                    elif not results and proc.returncode:
                        raise RuntimeError("fuzz worker failed to start: "
                                           + proc.stderr.read()[-2000:])
                    break
                try:
                    msg = json.loads(line)
                except ValueError:  # a case wrote to the worker's stdout descriptor
                    msg = {"stray": line}
                if "stray" in msg or not isinstance(msg, dict):
                    print(f"stray output on stdout during {current}: {line[:200]!r}",
                          file=sys.stderr)
                    continue
                if "begin" in msg:
                    current, began = msg["begin"], time.perf_counter()
                    continue
                p = msg["path"]
                results[p] = Result(meta[p][0], msg["kind"], msg["code"], msg["seconds"],
                                    msg["detail"], meta[p][1])
                if progress is not None:
                    progress(results[p])
                current, began = None, time.perf_counter()
            sel.close()
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            proc.stdout.close()
            proc.stderr.close()
            todo = [p for p in paths if p not in results]
    finally:
        if own:
            shutil.rmtree(workdir, ignore_errors=True)
    return [results[p] for p in paths]


def summarize(results: list[Result]) -> dict[str, int]:
    out: dict[str, int] = {}
    for r in results:
        out[r.kind] = out.get(r.kind, 0) + 1
    return dict(sorted(out.items()))


def as_dict(r: Result) -> dict:
    return asdict(r)


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--worker", required=True)
    ap.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT)
    ap.add_argument("--mem", type=int, default=DEFAULT_MEM_MB)
    ap.add_argument("--args")
    a = ap.parse_args()
    worker(a.worker, a.timeout, a.mem, json.loads(a.args) if a.args else None)
