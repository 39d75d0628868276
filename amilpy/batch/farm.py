"""Independent runs on every core, or on a Dask cluster (issue 14.5).

The runs of a listing's value lists and END groups, the points of a sweep that
does not carry its state, and the points of a parameter grid do not depend on each
other. `farm` hands them to worker processes on this machine (`jobs`) or to a Dask
distributed cluster (`scheduler`, the optional extra `amilpy[cluster]`). Each worker
gets the checked model once (pickled with the pool's initializer; scattered to
every Dask worker once) and keeps its generated functions between tasks, so a worker
compiles a model once per set of constants, as a serial run would.

Results come back in the order of the tasks, whatever order they finish in. A task
that raises (a fault in its data, say) comes back as an `Outcome` with the error's
text, labelled with its parameters; the others are kept. The same code runs each
task as a serial run does (`run.simulate`), so the results are the same, bit for
bit.
"""

from __future__ import annotations

import hashlib
import math
import os
import pickle
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from .. import interrupts, ir
from ..diagnostics import AmilError
from ..outcome import was_interrupted
from ..result import Run

# per worker process: token -> (model, its Cache)
_MODELS: dict[str, tuple[ir.Model, object]] = {}


@dataclass(frozen=True)
class Task:
    """One independent run. `measure`: a sweep's point only (the minimum and maximum
    of that variable after `settle` seconds), the run itself kept only with
    `keep_run`."""

    spec: ir.RunSpec
    options: object  # run.Options, without a progress callback
    label: str
    measure: str | None = None
    settle: float = 0.0
    keep_run: bool = True
    # what comes back instead of the run: reduce(run) as the outcome's point (a
    # module-level function or a partial of one: it goes to the workers pickled)
    reduce: Callable[[Run], object] | None = None


@dataclass
class Outcome:
    """What a task gave: the run (or None), a sweep's (min, max, status, t0, t_end,
    unsteadiness),
    or the error that stopped it (the task's label is not in it: the caller says
    which run or point it was)."""

    run: Run | None = None
    point: tuple | None = None
    error: str | None = None
    interrupted: bool = False  # Ctrl-C came before it finished


def default_jobs() -> int:
    """Every core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def farm(model: ir.Model, tasks: list[Task], jobs: int = 1, scheduler: str | None = None,
         done: Callable[[int, Outcome], None] | None = None, cache=None) -> list[Outcome]:
    """Run the tasks; their outcomes in the tasks' order. `done(i, outcome)` is called
    as each finishes (in the order they finish). With one job (or one task) they run
    here, one after the other, with `cache` (an `api.Model`'s)."""
    if scheduler or (jobs > 1 and len(tasks) > 1):
        # no progress lines from other processes
        tasks = [replace(t, options=replace(t.options, progress=None)) for t in tasks]
    if scheduler:
        return _on_dask(model, tasks, scheduler, done)
    if jobs <= 1 or len(tasks) <= 1:
        if cache is None:
            from ..run import Cache

            cache = Cache()
        out = []
        for i, task in enumerate(tasks):
            out.append(_execute(model, cache, task))
            if done is not None:
                done(i, out[-1])
            if out[-1].interrupted:  # Ctrl-C: keep what was computed, start nothing new
                return out + [Outcome(error="interrupted before it started", interrupted=True)
                              for _ in tasks[i + 1:]]
        return out
    return _on_processes(model, tasks, jobs, done)


# ------------------------------------------------------------------------ workers

def _token(blob: bytes) -> str:
    return hashlib.sha256(blob).hexdigest()[:16]


def _install(token: str, blob: bytes, ignore_interrupt: bool = False) -> None:
    """A worker's copy of the model and its cache (pool initializer). A pool's worker
    leaves Ctrl-C to the parent, which ends it."""
    if ignore_interrupt:
        import signal

        # a forked worker has the command line's handlers: Ctrl-C is the parent's to
        # handle, and the parent's terminate() must end the worker; the signals were
        # blocked while it started (`_STARTING`), and are taken as set here
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        for sig in (signal.SIGTERM, getattr(signal, "SIGHUP", None)):
            if sig is not None:
                signal.signal(sig, signal.SIG_DFL)
        if hasattr(signal, "pthread_sigmask"):
            signal.pthread_sigmask(signal.SIG_UNBLOCK, _starting_signals())
    if token not in _MODELS:
        from ..run import Cache

        _MODELS[token] = (pickle.loads(blob), Cache())  # noqa: S301 - our own pickle


def _starting_signals() -> set:
    """The signals held back while the workers start: one arriving in a worker
    before its initializer set its handlers ran the command line's handler there,
    and the pool waited for that worker for ever."""
    import signal

    return {s for s in (signal.SIGINT, signal.SIGTERM, getattr(signal, "SIGHUP", None))
            if s is not None}


def execute(token: str, task: Task) -> Outcome:
    """One task in a worker, on the model installed there."""
    model, cache = _MODELS[token]
    return _execute(model, cache, task)


def execute_group(token: str, tasks: list[Task]) -> list[Outcome]:
    """Several tasks in a worker, one after the other: for runs of a millisecond,
    which a task each would spend as much in handing over as in running."""
    model, cache = _MODELS[token]
    return [_execute(model, cache, task) for task in tasks]


# tasks per hand-over to a worker: enough that each worker gets GROUPS of them
# (the pool balances the load), at most MAX_GROUP
GROUPS, MAX_GROUP = 8, 64


def groups(count: int, jobs: int) -> list[range]:
    """The tasks' indices cut into hand-overs (see GROUPS)."""
    size = max(1, min(MAX_GROUP, count // (jobs * GROUPS)))
    return [range(k, min(count, k + size)) for k in range(0, count, size)]


def _execute(model: ir.Model, cache, task: Task) -> Outcome:
    from ..run import simulate

    try:
        run = simulate(model, task.spec, task.options, cache)
    except AmilError as exc:
        if exc.path is None:
            exc.path = model.path
        return Outcome(error=exc.render())
    except Exception as exc:  # noqa: BLE001 - reported with its parameters, others kept
        return Outcome(error=f"{type(exc).__name__}: {exc}")
    stopped = was_interrupted(run.message)
    if task.reduce is not None:
        return Outcome(point=task.reduce(run), interrupted=stopped)
    if task.measure is None:
        return Outcome(run=run, interrupted=stopped)
    t0 = float(run.times[0]) if len(run.times) else float("nan")
    lo, hi = extent(run, task.measure)
    return Outcome(run=run if task.keep_run else None,
                   point=(lo, hi, str(run.status), t0, float(run.t_end),
                          unsteadiness(run, task.measure, task.settle)),
                   interrupted=stopped)


def extent(run: Run, measure: str) -> tuple[float, float]:
    """The least and greatest value of `measure` after the settling time, located
    between the output instants like RANGE (`Options.extrema`): the peak of a lightly
    damped resonance falls between rows at any OUTDEL."""
    lo, _, hi, _ = run.extrema.get(measure, (float("nan"),) * 4)
    return lo, hi


def unsteadiness(run: Run, measure: str, settle: float) -> float:
    """How far `measure` is from a settled oscillation after the settling time: the
    difference of its half peak-to-peak over the two halves of that window, from the
    rows (their sampling error is alike in both halves). A jump search sets a step
    of the characteristic against it: an orbit still drifting, or one that is not
    periodic, moves from point to point by about this much."""
    t = run.times
    if not len(t):
        return math.nan
    t0 = float(t[0]) + settle
    mid = 0.5 * (t0 + float(t[-1]))
    y = np.asarray(run.values[measure], dtype=float)
    first, second = y[(t >= t0) & (t <= mid)], y[t >= mid]
    if len(first) < 2 or len(second) < 2:
        return math.nan
    return 0.5 * abs(float(np.ptp(first)) - float(np.ptp(second)))


def _on_processes(model: ir.Model, tasks: list[Task], jobs: int,
                  done: Callable | None) -> list[Outcome]:
    import multiprocessing as mp
    import signal
    from concurrent.futures import ProcessPoolExecutor, as_completed

    blob = pickle.dumps(model)
    token = _token(blob)
    # fork where there is one: the workers start with amilpy, NumPy and SciPy imported
    context = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else None)
    out: list[Outcome | None] = [None] * len(tasks)
    # (the workers are forked at the first submit, with this thread's signal mask: a
    # signal that comes meanwhile waits, here for the loop below, in a worker for
    # its initializer)
    blocking = hasattr(signal, "pthread_sigmask")
    if blocking:
        signal.pthread_sigmask(signal.SIG_BLOCK, _starting_signals())
    pool = None
    try:
        try:
            pool = ProcessPoolExecutor(max_workers=min(jobs, len(tasks)), mp_context=context,
                                       initializer=_install, initargs=(token, blob, True))
            futures = {pool.submit(execute_group, token, [tasks[i] for i in group]): group
                       for group in groups(len(tasks), jobs)}
        finally:
            if blocking:  # (one held back is raised here, and handled below)
                signal.pthread_sigmask(signal.SIG_UNBLOCK, _starting_signals())
        interrupts.check()  # (one swallowed while the pool started)
        for future in as_completed(futures):
            group = futures[future]
            try:
                got = future.result()
            except Exception as exc:  # noqa: BLE001 - a worker that died
                got = [Outcome(error=f"the worker failed: {exc}") for _ in group]
            for i, outcome in zip(group, got, strict=True):
                out[i] = outcome
                if done is not None:
                    done(i, outcome)
            interrupts.check()
    except KeyboardInterrupt:
        # Ctrl-C: the finished runs are kept; the workers are ended, their runs lost
        interrupts.handled()
        for child in mp.active_children():
            child.terminate()
        if pool is not None:
            # (a worker ended while it was sending its results leaves the pool's
            # reading thread waiting for the rest of that message for ever -- a Ctrl-C
            # under load hung so; with this process's copy of the pipe's writing end
            # closed, the workers' gone with them, it reads the pipe's end instead and
            # stops, the pool broken, as it is)
            writer = getattr(getattr(pool, "_result_queue", None), "_writer", None)
            if writer is not None:
                writer.close()
            # (and the pool's thread, which then sees its workers gone, joined: a
            # shutdown that does not wait forgets it, and Python's exit would wake it
            # through a pipe it is closing, printing a traceback after the last line)
            try:
                pool.shutdown(wait=True, cancel_futures=True)
            except KeyboardInterrupt:  # (a second Ctrl-C: the runs kept matter more)
                pass
        return [o if o is not None else Outcome(
            error="interrupted before it finished", interrupted=True) for o in out]
    pool.shutdown()
    return [o if o is not None else Outcome(error="not run") for o in out]


CONNECT_SECONDS = 30.0  # for the scheduler to answer, and for its first worker


def _check_address(address: str) -> None:
    """Refuse what is no scheduler's address before a Client is made of it: one
    that fails on a malformed address is left half made, and its clean-up at exit
    waited on a stopped event loop (the command hung after its message)."""
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, location = parse_address(address)
        if scheme in ("tcp", "tls", "ws", "wss", "ucx"):
            parse_host_port(location)
    except (ValueError, TypeError) as exc:
        raise AmilError(f"--scheduler {address!r} is not a scheduler's address ({exc}): "
                        "write it as tcp://HOST:PORT") from None


def _on_dask(model: ir.Model, tasks: list[Task], address: str,
             done: Callable | None) -> list[Outcome]:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise AmilError("--scheduler needs Dask: pip install 'amilpy[cluster]'") from None
    blob = pickle.dumps(model)
    token = _token(blob)
    _check_address(address)
    try:
        client = Client(address, timeout=CONNECT_SECONDS, set_as_default=False)
    except (OSError, ValueError, TypeError) as exc:
        raise AmilError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    try:
        try:  # (a scheduler with no worker would take the runs and never run them)
            client.wait_for_workers(1, timeout=CONNECT_SECONDS)
        except (TimeoutError, OSError):
            raise AmilError(f"the Dask scheduler at {address} has no workers (waited "
                            f"{CONNECT_SECONDS:g} s): start one, e.g. dask worker "
                            f"{address}") from None
        shipped = client.scatter((token, blob), broadcast=True)  # once per worker
        futures = [client.submit(_dask_task, shipped, task, pure=False) for task in tasks]
        index = {f.key: i for i, f in enumerate(futures)}
        out: list[Outcome | None] = [None] * len(tasks)
        with client.as_current():
            for future in as_completed(futures):
                i = index[future.key]
                try:
                    out[i] = future.result()
                except Exception as exc:  # noqa: BLE001 - a worker that died
                    out[i] = Outcome(error=f"the worker failed: {exc}")
                if done is not None:
                    done(i, out[i])
        return [o if o is not None else Outcome(error="not run") for o in out]
    finally:
        client.close()


def _dask_task(shipped: tuple[str, bytes], task: Task) -> Outcome:
    token, blob = shipped
    _install(token, blob)
    return execute(token, task)


def run_tasks(model: ir.Model, specs: list[ir.RunSpec], options, jobs: int,
              scheduler: str | None, done=None, cache=None) -> list[Outcome]:
    """`farm` for a listing's runs, one task per spec."""
    opts = replace(options, progress=None)
    tasks = [Task(spec, opts, f"run {spec.label!r}" if spec.label else f"run {k + 1}")
             for k, spec in enumerate(specs)]
    return farm(model, tasks, jobs, scheduler, done, cache)


def failed_run(spec: ir.RunSpec, method: str, message: str) -> Run:
    """A run that could not start (a fault in its data): no rows, its message."""
    from ..result import Status

    empty = np.empty(0)
    return Run(label=spec.label, params=dict(spec.data), constants={}, times=empty,
               values={}, outdel_mask=np.empty(0, bool), prdel_mask=np.empty(0, bool),
               events=[], status=Status.FAILED, message=message, final={}, stats={},
               method=method, rtol=float("nan"), atol=float("nan"), titles=list(spec.titles),
               reports=list(spec.reports))
