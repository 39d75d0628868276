"""--check-accuracy: the run against itself with a 100 times smaller tolerance (a
fixed step: DELT / 4). The difference it reports must be the run's own error, which
closed forms give here; a variation that exists only because of the tolerance must
be called numerical."""

import math

import numpy as np
import pytest

import amilpy
from amilpy.cli import main
from amilpy.output.words import WORDS, accuracy_lines

# X = exp(-TIME); Y counts the time since X fell below 0.5 (TIME ln 2: a located switch)
DECAY = """TITLE DECAY
X = INTGRL(1.0, -X)
Y = INTGRL(0.0, FSW(X - 0.5, 1.0, 0.0, 0.0))
TIMER FINTIM = 3.0, OUTDEL = 0.01
PRINT X, Y
END
"""

# an undamped oscillator: E is 0.5 exactly; whatever it does, the integrator did
OSCILLATOR = """TITLE OSCILLATOR
X = INTGRL(1.0, V)
V = INTGRL(0.0, -X)
E = 0.5*(X*X + V*V)
TIMER FINTIM = 20.0, OUTDEL = 1.0
PRINT X, E
END
"""


def _check(text, **kw):
    model = amilpy.loads(text)
    runs = model.run(**kw)
    check, = model.check_accuracy(runs)
    return runs[0], check, {v.name: v for v in check.variables}


def test_the_difference_is_the_run_s_own_error():
    # the loose run's true error against exp(-t); the tight one's is ~100 times
    # smaller, so the difference between them is the loose error to a few percent
    # (a tolerance does not bound the error proportionally: 50 % either way allowed)
    run, check, by = _check(DECAY, method="RKS", rtol=1e-5, atol=1e-8)
    grid = run.outdel_mask | run.prdel_mask
    true = float(np.max(np.abs(run["X"][grid] - np.exp(-run.t[grid]))))
    assert 0.5 * true < by["X"].largest < 1.5 * true
    assert check.how == "RELERR 1e-07, ABSERR 1e-10"
    assert by["X"].digits == int(math.floor(-math.log10(by["X"].largest / 1.0)))
    assert not by["X"].numerical
    # the switch at X = 0.5 (TIME ln 2): the same event, shifted by about the error there
    assert check.events == check.events_tight == 1
    assert check.shift < 10 * abs(run.events[0].time - math.log(2.0)) + 1e-12


def test_a_variation_that_only_the_step_makes_is_called_numerical():
    # Euler on the oscillator multiplies X^2 + V^2 by exactly (1 + h^2) a step, so
    # E = 0.5 (1 + h^2)^(TIME/h): all of E's growth is the method's, and the check's
    # difference at TIME 20 is 0.5 ((1 + h^2)^(20/h) - (1 + h^2/16)^(80/h)) to rounding
    h = 0.01
    text = OSCILLATOR.replace("OUTDEL = 1.0", f"OUTDEL = 1.0, DELT = {h}")
    run, check, by = _check(text, method="EULER")
    e = by["E"]
    exact = 0.5 * ((1 + h * h) ** (20 / h) - (1 + h * h / 16) ** (80 / h))
    assert e.largest == pytest.approx(exact, rel=1e-9) and e.at == 20.0
    assert e.numerical
    assert any(line.startswith("E: its variation") and "is numerical" in line
               for line in accuracy_lines(check, WORDS["en"]))


def test_a_fixed_step_method_is_checked_with_a_quarter_of_delt():
    # Euler's error is proportional to DELT: err(h) - err(h/4) = 3/4 err(h) to O(h^2)
    text = DECAY.replace("TIMER FINTIM = 3.0, OUTDEL = 0.01",
                         "TIMER FINTIM = 3.0, OUTDEL = 0.01, DELT = 0.001")
    run, check, by = _check(text, method="EULER")
    grid = run.outdel_mask | run.prdel_mask
    true = float(np.max(np.abs(run["X"][grid] - np.exp(-run.t[grid]))))
    assert check.how == "DELT 0.00025"
    assert by["X"].largest == pytest.approx(0.75 * true, rel=0.02)


def test_the_command_line_prints_the_check(tmp_path, capsys):
    path = tmp_path / "decay.amil"
    path.write_text(DECAY)
    assert main(["run", str(path), "--method", "RKS", "--rtol", "1e-5",
                 "--check-accuracy"]) == 0
    out = capsys.readouterr().out
    assert "ACCURACY CHECK" in out and "(RELERR 1e-07, ABSERR" in out
    assert "X: " in out and "significant digits stand" in out and "events: the same 1" in out


def test_the_check_runs_with_the_run_s_own_options():
    # a random draw seeded from outside and a shorter FINTIM: the tighter run must draw
    # the same numbers over the same span, or the comparison says nothing
    text = ("TITLE NOISE\nX = INTGRL(0.0, GAUSS(1, 0.0, 1.0) - X)\nPRINT X\n"
            "TIMER FINTIM = 10.0, OUTDEL = 0.1\nEND\n")
    model = amilpy.loads(text)
    runs = model.run(method="RKS", rtol=1e-6, atol=1e-9, seed=7, fintim=2.0)
    check, = model.check_accuracy(runs, seed=7, fintim=2.0)
    x, = check.variables
    assert x.digits >= 5 and not x.numerical  # the same noise: only the tolerance differs
    assert x.at <= 2.0 + 1e-12


def test_the_report_has_the_check_under_each_run_unless_asked_not_to(tmp_path):
    path = tmp_path / "decay.amil"
    path.write_text(DECAY)
    assert main(["report", str(path), "--out", str(tmp_path / "r"), "--format", "md"]) == 0
    text = (tmp_path / "r" / "decay_report.md").read_text()
    assert "Accuracy check (RELERR 1e-12, ABSERR" in text
    assert "X: " in text and "significant digits stand" in text
    assert main(["report", str(path), "--out", str(tmp_path / "n"), "--format", "md",
                 "--no-accuracy-check"]) == 0
    assert "Accuracy check" not in (tmp_path / "n" / "decay_report.md").read_text()
    assert main(["report", str(path), "--out", str(tmp_path / "p"), "--format", "md",
                 "--lang", "pl"]) == 0
    polish = (tmp_path / "p" / "decay_report.md").read_text(encoding="utf-8")
    assert "Sprawdzenie dokładności" in polish and "cyfr znaczących" in polish
