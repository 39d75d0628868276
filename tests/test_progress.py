"""One progress interface: every long computation gives the same `Report` to the same
kind of callable (`amilpy.progress`), and the command line's progress line reads
them all."""

import io

import pytest

import amilpy
from amilpy.cli.console import Progress
from amilpy.progress import TASKS, Report

# a forced, damped oscillator: its steady orbit has the forcing's period
FORCED = """PARAM W = 1.0
X = INTGRL(0.0, V)
V = INTGRL(0.0, COS(W*TIME) - 0.1*V - X)
TIMER FINTIM = 40.0, OUTDEL = 0.05
OUTPUT X
END
"""


def _collect():
    seen: list[Report] = []
    return seen, seen.append


def test_runs_report_their_time_and_each_finished_run():
    seen, progress = _collect()
    amilpy.loads(FORCED.replace("PARAM W = 1.0", "PARAM W = (1.0, 2.0)")).run(
        progress=progress)
    times = [r for r in seen if r.task == "run"]
    assert times and all(0.0 <= r.done <= r.total == 40.0 for r in times)
    assert all({"events", "steps"} <= set(r.facts) for r in times)
    finished = [r for r in seen if r.task == "runs"]
    assert [(r.done, r.total, r.facts["index"]) for r in finished] == [(1, 2, 0), (2, 2, 1)]


def test_a_sweep_reports_its_points_and_its_runs_to_the_same_callable():
    seen, progress = _collect()
    amilpy.loads(FORCED).sweep("W", [0.8, 1.0, 1.2], settle=30.0, measure="X",
                               progress=progress)
    points = [(r.done, r.total, r.facts["name"], r.facts["value"]) for r in seen
              if r.task == "sweep"]
    assert points == [(1, 3, "W", 0.8), (2, 3, "W", 1.0), (3, 3, "W", 1.2)]
    assert any(r.task == "run" for r in seen)


def test_newton_and_the_response_curve_report_their_steps():
    seen, progress = _collect()
    model = amilpy.loads(FORCED)
    model.periodic(period="2*PI/W", progress=progress)
    newton = [r for r in seen if r.task == "periodic"]
    assert [r.done for r in newton] == list(range(len(newton))) and len(newton) >= 2
    assert newton[-1].facts["residual"] < newton[0].facts["residual"]
    seen.clear()
    model.response("W", 0.9, 1.1, period="2*PI/W", progress=progress)
    points = [r for r in seen if r.task == "response"]
    assert points and all(r.total is None and r.facts["name"] == "W" for r in points)
    assert all(0.9 - 1e-9 <= r.facts["value"] <= 1.1 + 1e-9 for r in points)


def test_an_unknown_task_is_refused():
    with pytest.raises(ValueError, match="unknown progress task"):
        Report("fitting", 1.0)
    assert set(TASKS) == {"run", "runs", "sweep", "periodic", "response", "fit"}


def test_the_progress_line_reads_every_task(monkeypatch):
    err = io.StringIO()
    err.isatty = lambda: True
    monkeypatch.setattr("sys.stderr", err)
    line = Progress(True)
    line.start -= 10.0  # (it shows a run's TIME after the first second)
    line(Report("sweep", 1, 3, {"name": "W", "value": 0.8}))
    line(Report("run", 20.0, 40.0, {"events": 2, "steps": 100}))
    line(Report("runs", 1, 2, {"index": 0}))
    line(Report("periodic", 3, None, {"residual": 1e-9}))
    line(Report("response", 7, None, {"name": "W", "value": 1.05, "residual": 1e-10}))
    line(Report("fit", 4, None, {"value": "K = 0.8"}))
    text = err.getvalue()
    for shown in ("W = 0.8 done (1/3)", "W point 2/3  TIME 20 / 40  ( 50.0%)  events 2",
                  "run 1 finished (1 of 2)", "periodic: Newton step 3, residual 1.00e-09",
                  "response: W = 1.05  point 7  residual 1.0e-10",
                  "fit: evaluation 4  K = 0.8"):
        assert shown in text
