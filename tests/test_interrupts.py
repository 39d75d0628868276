"""A Ctrl-C that a library swallows is not lost (issue 27 point 1).

The command line turns SIGINT into KeyboardInterrupt wherever Python is. Inside a
compiled module's initialization that comes out as an ImportError, and libraries
import their optional parts under `except ImportError`: the interrupt vanished
and a farmed run went on to its end (seen once in the Ctrl-C scan of
tests/test_farm.py, at 0.4 s). The handler now also notes the signal
(`amilpy.interrupts`), and the loops look again between chunks, runs and
results. Here a swallow is made to happen at a chosen place, so the test does not
depend on when a signal lands."""

from __future__ import annotations

import signal

import pytest

import amilpy
from amilpy import cli, interrupts
from amilpy.batch.farm import default_jobs

OSCILLATOR = """TITLE TWO RUNS OF AN OSCILLATOR
PARAM K = (1.0, 4.0)
DYNAMIC
   X = INTGRL(1.0, V)
   V = INTGRL(0.0, -K*X)
TIMER FINTIM = 50.0, OUTDEL = 0.5
PRINT X
END
"""


def _swallowed() -> None:
    """What a library's `try: import ... except ImportError: pass` does to the
    command line's interrupt: noted, raised, and caught on the way."""
    interrupts.arrived(signal.SIGINT)
    try:
        raise ImportError("initialization failed")  # (the KeyboardInterrupt, as it comes out)
    except ImportError:
        pass


@pytest.fixture(autouse=True)
def _clear():
    yield
    interrupts.handled()


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RK4", "BDF"])
def test_a_swallowed_interrupt_ends_the_run_at_its_next_chunk(method):
    """Swallowed before the run starts: the run still ends interrupted, at its first
    look (after its first chunk of steps: AUTO takes up to 4,096 rows in one call
    to LSODA), with its rows kept, and the interrupt is handled (a later run is not
    interrupted by it)."""
    model = amilpy.loads(OSCILLATOR)
    _swallowed()
    runs = model.run(method=method, advice=False)
    assert len(runs) == 1, "an interrupted run starts nothing new"
    run = runs[0]
    assert not run.ok and run.message.startswith("interrupted at TIME = ")
    assert run.values["X"][0] == 1.0 and run.t_end < 50.0
    assert not interrupts.pending()
    assert all(r.ok for r in model.run(method=method, advice=False))


@pytest.mark.skipif(default_jobs() < 2, reason="needs two cores to farm two runs")
def test_a_swallowed_interrupt_ends_a_farmed_run():
    """Swallowed while the workers start: the farm stops waiting for them at once,
    and the runs are said to be interrupted, not run to their end."""
    model = amilpy.loads(OSCILLATOR)
    _swallowed()
    runs = model.run(jobs=2, advice=False)
    assert [r.message for r in runs] == ["interrupted before it finished"]  # (the
    # list ends at the first interrupted run, as one after the other)
    assert not interrupts.pending()


def test_the_command_line_says_interrupted_when_nothing_looked_again(
        tmp_path, monkeypatch, capsys):
    """Swallowed after the last look (here: as the printout is written), the
    command still says 'interrupted' and exits 3; what it wrote is complete."""
    from amilpy.output import printout

    path = tmp_path / "osc.amil"
    path.write_text(OSCILLATOR)
    write_runs = printout.write_runs

    def swallowing(*args, **kwargs):
        _swallowed()
        return write_runs(*args, **kwargs)

    monkeypatch.setattr(printout, "write_runs", swallowing)
    code = cli.main(["run", str(path)])
    out, err = capsys.readouterr()
    assert code == cli.EXIT_FAILED
    assert f"{path}: interrupted" in err
    assert "5.000000E+01" in out  # both runs printed to FINTIM = 50
    assert not interrupts.pending()


def test_the_command_line_ends_a_swallowed_interrupt_in_a_run(tmp_path, monkeypatch,
                                                              capsys):
    """Swallowed while the first of two runs is set up: that run ends interrupted
    with its rows, the second is not started, exit 3."""
    import amilpy.run as run_package

    path = tmp_path / "osc.amil"
    path.write_text(OSCILLATOR)
    simulate = run_package.simulate
    calls = []

    def swallowing(*args, **kwargs):
        calls.append(1)
        if len(calls) == 1:
            _swallowed()
        return simulate(*args, **kwargs)

    monkeypatch.setattr(run_package, "simulate", swallowing)
    code = cli.main(["run", str(path), "--quiet", "--jobs", "1"])
    err = capsys.readouterr().err
    assert code == cli.EXIT_FAILED and len(calls) == 1
    assert "run 'K = 1': interrupted at TIME = " in err and "K = 4" not in err


def test_a_second_ctrl_c_waits_for_the_files_and_a_third_ends_the_command():
    """A user pressing Ctrl-C twice: the second came while the first was being turned
    into a partial run and, raised there, lost the rows and every file (the probe:
    exit 3, no CSV). The second is now held back until the files are written (then
    the command stops, exit 3); a third is raised, for a command that does not end."""
    from amilpy.cli.console import Signals

    signals = Signals()
    with pytest.raises(KeyboardInterrupt):
        signals._handler(signal.SIGINT, None)
    signals._handler(signal.SIGINT, None)  # (held back: no exception)
    assert signals.held_back == signal.SIGINT
    with pytest.raises(KeyboardInterrupt):
        signals._handler(signal.SIGINT, None)


def test_an_auto_chunk_takes_a_quarter_second_at_most(monkeypatch):
    """A Ctrl-C inside one of AUTO's odeint calls loses that call's rows (odeint gives
    back nothing of a call an exception ends), and without --max-time a call could
    take 4,096 output instants however slow they were. Every AUTO stepper is now
    given CHUNK_SECONDS, and sizes its next chunk from the time its chunks took: at
    1 ms an instant a chunk is at most 250 instants (the clock is the stepper's own
    bookkeeping here, set by hand: no test waits on a clock)."""
    import numpy as np

    from amilpy import steppers
    from amilpy.run import segment
    from amilpy.steppers.odeint import OdeintStepper

    given = []
    real = steppers.make_stepper

    def spy(*args, **kw):
        given.append(kw.get("chunk_seconds"))
        return real(*args, **kw)

    monkeypatch.setattr(segment, "make_stepper", spy)
    assert amilpy.loads(OSCILLATOR).run(method="AUTO", advice=False)[0].ok
    assert given and all(s == segment.CHUNK_SECONDS == 0.25 for s in given)
    stepper = OdeintStepper(lambda t, y: -y, 0.0, np.ones(1), 100.0, np.arange(1.0, 100.0),
                            rtol=1e-6, atol=1e-9, max_step=np.inf, first_step=None,
                            chunk=4096, chunk_seconds=0.25)
    stepper._instants, stepper._seconds, stepper._steps = 1000, 1.0, 1000
    assert stepper._chunk_size(10**9) == 250
