"""Independent runs on every core and on a Dask cluster (issue 14.5): the same runs,
bit for bit, in the same order as one after the other; a run that fails is reported
with its parameters and the others are kept."""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import amilpy
from amilpy.batch.farm import default_jobs

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HOIST = os.path.join(HERE, "models", "hoist_backlash.amil")

LISTS = """TITLE A DAMPED OSCILLATOR, FOUR DAMPINGS
PARAM ZETA = (0.05, 0.1, 0.2, 0.4), W = 6.0
DYNAMIC
   X = INTGRL(1.0, V)
   V = INTGRL(0.0, -2.0*ZETA*W*V - W*W*X + FSW(X - 0.5, 0.0, 0.0, 1.0))
TIMER FINTIM = 4.0, OUTDEL = 0.01
END
"""


def _same(a, b) -> bool:
    return (a.label == b.label and a.status == b.status and
            np.array_equal(a.times, b.times) and
            all(np.array_equal(a.values[k], b.values[k]) for k in a.values) and
            [(e.time, e.new) for e in a.events] == [(e.time, e.new) for e in b.events])


def test_value_lists_on_two_processes_equal_the_serial_runs():
    """The four runs of a PARAM value list, on two worker processes, are the serial
    runs bit for bit (times, every value, every event), in the listing's order."""
    model = amilpy.loads(LISTS)
    serial = model.run(advice=False)
    farmed = amilpy.loads(LISTS).run(advice=False, jobs=2)
    assert [r.label for r in farmed] == [r.label for r in serial] == \
        ["ZETA = 0.05", "ZETA = 0.1", "ZETA = 0.2", "ZETA = 0.4"]
    assert all(_same(a, b) for a, b in zip(serial, farmed, strict=True))


def test_a_failing_run_is_reported_and_the_others_kept():
    """A run whose data cannot be evaluated (INITIAL divides by ZETA = 0) comes back
    FAILED, named by its parameters; the runs before and after it are kept, on worker
    processes and one after the other alike."""
    text = LISTS.replace("(0.05, 0.1, 0.2, 0.4)", "(0.05, 0.0, 0.2)").replace(
        "DYNAMIC", "INITIAL\n   TAU = 1.0/ZETA\nDYNAMIC")
    runs = amilpy.loads(text).run(advice=False, jobs=2)
    assert [r.ok for r in runs] == [True, False, True]
    assert "division by zero" in runs[1].message and runs[1].label == "ZETA = 0"
    assert "ZETA = 0" not in runs[1].message  # the label is said once, by whoever prints
    assert len(runs[2].times) == 401
    # one after the other in this process, the same: the fault does not stop the others
    serial = amilpy.loads(text).run(advice=False, jobs=1)
    assert [r.ok for r in serial] == [True, False, True]
    assert serial[1].message == runs[1].message
    assert all(_same(a, b) for a, b in zip(serial, runs, strict=True))


def test_sweep_and_grid_on_processes_equal_serial():
    """A sweep without a carried state and a grid of two data values: every point on
    two processes equals the serial point, in the points' order."""
    model = amilpy.loads(LISTS)
    values = [4.0, 5.0, 6.0, 7.0]
    one = model.sweep("W", values, measure="X", settle=1.0)
    two = model.sweep("W", values, measure="X", settle=1.0, jobs=2)
    assert one.points == two.points
    from amilpy.batch.sweep import sweep

    grid = sweep(model, "W", values, measure="X", grid=("ZETA", [0.1, 0.3]), jobs=2)
    serial = sweep(model, "W", values, measure="X", grid=("ZETA", [0.1, 0.3]))
    assert grid.points == serial.points
    assert [(p.value, p.second) for p in grid.points] == \
        [(v, z) for z in (0.1, 0.3) for v in values]


def test_grid_from_the_command_line(tmp_path):
    """`amilpy sweep FILE A=... B=...`: a grid, one row per pair, in the CSV too."""
    from amilpy.cli import main

    path = tmp_path / "osc.amil"
    path.write_text(LISTS.replace("(0.05, 0.1, 0.2, 0.4)", "0.1"))
    csv = tmp_path / "grid.csv"
    assert main(["sweep", str(path), "W=4:6:1", "ZETA=0.1:0.2:0.1", "--measure", "X",
                 "--csv", str(csv), "--quiet", "--jobs", "2"]) == 0
    rows = csv.read_text().splitlines()
    assert rows[0].split(",")[:3] == ["DIRECTION", "W", "ZETA"]
    assert len(rows) == 1 + 3 * 2


def _read_until(fd: int, text: str | None, proc, timeout: float = 300.0) -> str:
    """What a pseudo-terminal gives until `text` appears (None: until it closes)."""
    got, end = "", time.monotonic() + timeout
    while time.monotonic() < end and (text is None or text not in got):
        ready, _, _ = select.select([fd], [], [], 1.0)
        if not ready:
            if proc.poll() is not None and text is not None:
                break
            continue
        try:
            chunk = os.read(fd, 4096)
        except OSError:  # (EIO: the other end closed)
            break
        if not chunk:
            break
        got += chunk.decode(errors="replace")
    return got


@pytest.mark.skipif(default_jobs() < 2, reason="needs two cores to interrupt two runs")
def test_ctrl_c_keeps_the_finished_runs(tmp_path):
    """Ctrl-C during a farmed run: the runs that finished are printed, the others
    are reported interrupted, exit 3 (the run already printed loses nothing)."""
    path = tmp_path / "two.amil"
    # K = 1 takes a few thousand steps, K = 1000 a thousand times more
    # (RELERR 1E-6: the run times this test was sized with)
    path.write_text("PARAM K = (1.0, 1000.0, 2000.0)\nX = INTGRL(0.0, COS(K*TIME))\n"
                    "RELERR 1.0E-6\nTIMER FINTIM = 1.0E3, OUTDEL = 1.0\nPRINT X\nEND\n")
    env = dict(os.environ, PYTHONPATH=HERE)
    # stderr on a terminal, where the progress line says when a run has finished: the
    # interrupt waits for that (a fixed sleep failed on a busy machine)
    leader, follower = os.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "amilpy.cli", "run", str(path), "--jobs", "2",
                             "--method", "RKS"], stdout=subprocess.PIPE,
                            stderr=follower, text=True, env=env, start_new_session=True)
    os.close(follower)
    err = _read_until(leader, "run 1 finished", proc)
    os.killpg(proc.pid, signal.SIGINT)
    out, _ = proc.communicate(timeout=120)
    err += _read_until(leader, None, proc)
    os.close(leader)
    assert proc.returncode == 3, err
    assert "run 'K = 1000': interrupted before it finished" in err
    first = out.split("RUN 2")[0]
    assert "1.000000E+03" in first  # run 1 printed to its end, TIME = 1000


@pytest.mark.slow  # (about 10 s: 13 interrupted commands)
@pytest.mark.skipif(default_jobs() < 2, reason="needs two cores to farm two runs")
@pytest.mark.skipif(not os.path.isdir("/proc"), reason="finds the workers in Linux's /proc")
def test_ctrl_c_at_any_instant_of_a_farmed_run_ends_it(tmp_path):
    """Ctrl-C at instants from 0.3 s to 1.4 s after the command starts (loading,
    generating code, forking the workers, running), and once its workers exist: the
    command always ends, within a minute, and once the command line has its handlers
    (after its imports: 0.2 s here with compiled bytecode, longer in a fresh install),
    with exit 3 and no traceback. A Ctrl-C that came while the
    workers were being forked ran the command line's handler in a worker, and the
    command waited for it for ever; the workers now start with the signals held back.
    While loading, the command ends killed by SIGINT, as a shell expects.
    (The instants are a scan, not a wait: what is asserted holds at every one.)"""
    path = tmp_path / "two.amil"
    path.write_text("PARAM K = (1.0, 1000.0, 2000.0)\nX = INTGRL(0.0, COS(K*TIME))\n"
                    "RELERR 1.0E-6\nTIMER FINTIM = 1.0E3, OUTDEL = 1.0\nPRINT X\nEND\n")
    # (faulthandler: a command still running is made to write where each of its
    # processes is, SIGABRT, before it is killed; the failure shows it)
    env = dict(os.environ, PYTHONPATH=HERE, PYTHONFAULTHANDLER="1")
    codes = []
    for k in range(13):
        # (SIGINT as a shell leaves it to a command it starts in the foreground: a test
        # runner's worker may ignore it, and a child inherits that until amilpy's
        # own handler is installed, so a Ctrl-C during its imports would be lost)
        proc = subprocess.Popen([sys.executable, "-m", "amilpy.cli", "run", str(path),
                                 "--jobs", "2", "--method", "RKS", "--quiet"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=env, start_new_session=True,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        if k < 12:
            time.sleep(0.3 + 0.1 * k)
        else:  # (the last once its workers exist: the command line has its handlers then,
            # however long a fresh install's first imports take; at 1.5 s they had not,
            # once, in CI)
            _wait_for_a_child(proc)
        os.killpg(proc.pid, signal.SIGINT)
        try:
            _, err = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGABRT)
            try:
                _, err = proc.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                _, err = proc.communicate()
            pytest.fail(f"Ctrl-C {0.3 + 0.1 * k:.1f} s after the start: still running 60 s "
                        f"later; where its processes were:\n{err[-4000:]}")
        codes.append(proc.returncode)
        if "Traceback" in err:  # (Python's own interrupt while it imports amilpy's
            # modules, however long that takes on this machine; once main() runs, none.
            # NumPy reports an interrupt inside its own import as an ImportError, "could
            # not import module datetime": seen once in a fresh install's CI)
            assert ("KeyboardInterrupt" in err or "ImportError" in err) and \
                ", in main" not in err, (proc.returncode, err[-500:])
        else:  # (3: runs interrupted; killed by SIGINT, as a shell expects, while loading)
            assert proc.returncode in (3, -signal.SIGINT) and "interrupted" in err, err
    assert codes[-1] == 3


def _wait_for_a_child(proc: subprocess.Popen, limit: float = 60.0) -> None:
    """Until the process has a child process (a farm's worker), or has ended; Linux's
    /proc read every 10 ms, at most `limit` seconds."""
    deadline = time.monotonic() + limit
    while proc.poll() is None and time.monotonic() < deadline:
        for entry in os.listdir("/proc"):
            if not entry.isdigit():
                continue
            try:
                with open(f"/proc/{entry}/stat") as f:
                    parent = int(f.read().rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue
            if parent == proc.pid:
                return
        time.sleep(0.01)


def test_dask_cluster_equals_serial():
    """The same runs on a Dask cluster started in this process (no network beyond
    this machine): the serial runs, bit for bit, in their order."""
    distributed = pytest.importorskip("distributed")
    model = amilpy.loads(LISTS)
    serial = model.run(advice=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        farmed = amilpy.loads(LISTS).run(advice=False, scheduler=cluster.scheduler_address)
        points = model.sweep("W", [4.0, 5.0, 6.0], measure="X",
                             scheduler=cluster.scheduler_address)
    assert all(_same(a, b) for a, b in zip(serial, farmed, strict=True))
    assert points.points == model.sweep("W", [4.0, 5.0, 6.0], measure="X").points


def test_a_scheduler_address_that_is_none_is_refused_at_once():
    """`--scheduler nonsense` gave distributed's ValueError with a traceback, and the
    command then hung at exit (the half-made Client's clean-up waited on a stopped
    event loop). It is refused before any Client is made."""
    pytest.importorskip("distributed")
    from amilpy.diagnostics import AmilError

    with pytest.raises(AmilError, match="'nonsense' is not a scheduler's address"):
        amilpy.loads(LISTS).run(advice=False, scheduler="nonsense")


def test_a_scheduler_with_no_workers_is_said_not_waited_on(monkeypatch):
    """A scheduler with no worker takes the runs and never runs them: the command
    waited for ever. Now it waits CONNECT_SECONDS for a worker, then says so."""
    distributed = pytest.importorskip("distributed")
    from amilpy.batch import farm
    from amilpy.diagnostics import AmilError

    monkeypatch.setattr(farm, "CONNECT_SECONDS", 1.0)
    with distributed.LocalCluster(n_workers=0, processes=False,
                                  dashboard_address=None) as cluster:
        with pytest.raises(AmilError, match="has no workers"):
            amilpy.loads(LISTS).run(advice=False, scheduler=cluster.scheduler_address)


def test_a_montecarlo_on_a_dask_cluster_is_the_serial_one_bit_for_bit():
    """The draws are made before any run, from the seed alone: a Dask cluster gives
    the serial Monte Carlo's bands, final values and statuses exactly."""
    distributed = pytest.importorskip("distributed")
    listing = ("PARAM K = 1.0\nX = INTGRL(1.0, -K*X)\nTIMER FINTIM = 1.0, OUTDEL = 0.1\n"
               "PRINT X\nEND\n")
    dists = {"K": "lognormal(0, 0.5)"}
    serial = amilpy.loads(listing).montecarlo(dists, runs=40, seed=9)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        farmed = amilpy.loads(listing).montecarlo(dists, runs=40, seed=9,
                                                  scheduler=cluster.scheduler_address)
    assert np.array_equal(serial.bands, farmed.bands)
    assert np.array_equal(serial.final, farmed.final) and serial.status == farmed.status
