"""Measured data beside a run (`--data`): the observations are compared with the
run's own values at their instants -- rows put there and located like any other,
never an interpolation between output rows -- and a bad file is an error at its
line and column."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import ROOT
from test_sensitivity import SAMPLED  # (the sampled P control: U held over each CINT)

import amilpy
from amilpy.cli import main
from amilpy.diagnostics import AmilError
from amilpy.output.plot import draw, figure_specs
from amilpy.output.printout import format_runs

# x' = -K x, x(0) = 1: x = exp(-K t). OUTDEL 0.1 is far coarser than the instants
# observed, so a value interpolated between rows would be off by ~1e-3.
DECAY = """TITLE DECAY
PARAM K = (1.0, 2.0)
X = INTGRL(1.0, -K*X)
TIMER FINTIM = 1.0, OUTDEL = 0.1
PRINT X
OUTPUT X
END
"""


def _write(tmp_path, text: str, name: str = "obs.csv") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_the_simulated_values_are_the_run_at_the_observed_instants(tmp_path):
    """Observations at instants between the output rows: the simulated values are
    exp(-K t) at those instants to the default tolerance's accuracy (1e-9: the
    global error of RELERR 1e-10 on a decay), in both runs; residual = observed
    minus simulated, and the summary's RMS and largest residual follow from them."""
    t = [0.123, 0.4567, 0.999]
    obs = [0.9, 0.6, 0.4]
    data = _write(tmp_path, "TIME,X\n" + "".join(f"{a},{b}\n" for a, b in zip(t, obs, strict=True)))
    runs = amilpy.loads(DECAY).run(data=data)
    for run, k in zip(runs, (1.0, 2.0), strict=True):
        (c,) = run.observed
        want = np.exp(-k * np.array(t))
        assert c.name == "X" and list(c.t) == t and list(c.observed) == obs
        assert np.max(np.abs(c.simulated - want)) < 1e-9
        assert np.allclose(c.residual, np.array(obs) - want, atol=1e-9)
        assert c.rms == pytest.approx(math.sqrt(np.mean((np.array(obs) - want) ** 2)))
        assert c.largest == pytest.approx(np.max(np.abs(np.array(obs) - want)))
        # the OUTDEL table is the listing's: no row of the observations in it
        assert np.allclose(run.t, np.linspace(0.0, 1.0, 11))


def test_a_run_column_gives_each_run_its_own_observations(tmp_path):
    data = _write(tmp_path, "RUN;TIME;X\n1;0,5;0,6\n2;0,5;0,37\n2;0,25;0,6\n")
    first, second = amilpy.loads(DECAY).run(data=data)
    assert list(first.observed[0].t) == [0.5]
    assert list(second.observed[0].t) == [0.25, 0.5]
    assert second.observed[0].simulated == pytest.approx(np.exp([-0.5, -1.0]), abs=1e-9)


def test_the_printout_and_the_figure_show_the_observations(tmp_path):
    """A DATA table (TIME, variable, observed, simulated, residual) and a summary
    per variable under each run; on the figure of X, markers with the SD bars."""
    data = _write(tmp_path, "TIME,X,SD_X\n0.5,0.6,0.05\n0.75,0.45,0.05\n")
    runs = amilpy.loads(DECAY.replace("PARAM K = (1.0, 2.0)", "PARAM K = 1.0")).run(data=data)
    text = format_runs(runs)
    assert f"DATA ({data})" in text and "DATA SUMMARY" in text
    line = next(s for s in text.splitlines() if s.strip().startswith("0.75"))
    cells = line.split()
    assert cells[1] == "X" and float(cells[2]) == 0.45
    assert float(cells[3]) == pytest.approx(math.exp(-0.75), abs=1e-6)
    summary = text.split("DATA SUMMARY")[1].splitlines()[2].split()
    assert summary[:2] == ["X", "2"]
    fig = draw(runs, figure_specs(runs[0])[0])
    (bars,) = fig.axes[0].containers
    x, y = bars.lines[0].get_data()
    assert list(x) == [0.5, 0.75] and list(y) == [0.6, 0.45]
    assert bars.has_yerr


@pytest.mark.parametrize("text, where, words", [
    ("TIME,X3\n0.5,1\n", "obs.csv:1:6", "'X3' names no variable"),
    ("TIME;X\n0,5;0,6\n0,7;abc\n", "obs.csv:3:5", "'abc' is not a number"),
    ("TIME,X\n0.5,nan\n", "obs.csv:2:5", "'nan' is not a number"),
    ("TIME,X\n0.5,0.6\n1.5,0.2\n", "obs.csv:3:1", "TIME 1.5 is outside run 1"),
    ("TIME,X,RUN\n0.5,0.6,3\n", "obs.csv:2:9", "RUN must be a run number from 1 to 2"),
    ("X\n0.5\n", "obs.csv:1:1", "no TIME column"),
    ("TIME,X,SD_X\n0.5,0.6,0\n", "obs.csv:2:9", "SD_X must be a positive number"),
])
def test_a_bad_data_file_is_an_error_at_its_line_and_column(tmp_path, capsys, text, where,
                                                            words):
    listing = _write(tmp_path, DECAY, "decay.amil")
    data = _write(tmp_path, text)
    assert main(["run", listing, "--data", data, "--quiet"]) == 1
    err = capsys.readouterr().err
    assert f"{tmp_path}/{where}: error:" in err and words in err, err
    assert "Traceback" not in err


def test_an_acsl_program_has_a_row_at_every_observation(tmp_path):
    """An observation between two communication instants is a row of its own: the
    states there and what the code last left, no code run at it. U = -KP X is sampled
    by DYNAMIC every CINT = 0.25 and held, so X(k H + s) = X(k H) (1 - KP s) with
    X(k H) = X0 (1 - KP H)^k; at 0.6, U is still -KP X(0.5). On the CINT grid the
    run is the run without observations."""
    model = amilpy.loads(SAMPLED, "sampled.csl")
    run = model.run(advice=False, data=_write(tmp_path, "T,X,U\n0.6,1.0,1.0\n1.0,1.0,1.0\n"))[0]
    x, u = run.observed
    xk = 2.0 * (1 - 0.8 * 0.25) ** 2  # X(0.5)
    assert list(x.t) == [0.6, 1.0]
    assert x.simulated[0] == pytest.approx(xk * (1 - 0.8 * 0.1), rel=1e-12)
    assert u.simulated[0] == pytest.approx(-0.8 * xk, rel=1e-12)
    assert x.simulated[1] == pytest.approx(2.0 * (1 - 0.8 * 0.25) ** 4, rel=1e-12)
    plain = model.run(advice=False)[0]
    assert len(run.times) == len(plain.times) + 1  # (1.0 is a CINT instant already)
    assert run.values["U"][run.outdel_mask] == pytest.approx(plain.values["U"], rel=1e-12)


def test_an_euler_program_has_rows_at_its_steps_only(tmp_path):
    """IALG 3 (Euler, step-point mode) has no state between its steps: an observation
    there is refused, saying what to change."""
    model = amilpy.load(f"{ROOT}/models/examples/oral_dosing.csl")
    name = model.ir.states[0].name
    with pytest.raises(AmilError, match="no row at TIME 1.25") as err:
        model.run(method="RECT", data=_write(tmp_path, f"T,{name}\n1.25,1.0\n", "between.csv"))
    assert "make CINT divide" in err.value.diagnostics[0].hint


def test_the_report_has_the_observations_section(tmp_path, capsys):
    listing = _write(tmp_path, DECAY.replace("PARAM K = (1.0, 2.0)", "PARAM K = 1.0"),
                     "decay.amil")
    data = _write(tmp_path, "TIME,X\n0.5,0.6\n")
    assert main(["report", listing, "--data", data, "--format", "md",
                 "--no-accuracy-check"]) == 0
    md = (tmp_path / "decay_report.md").read_text()
    assert "**Observations against the run (obs.csv)**" in md
    assert "| 0.5 | X | 6.000000E-01 |" in md


def test_a_trailing_separator_is_no_column_and_errors_point_at_the_time_cell(tmp_path):
    """A spreadsheet writes `TIME;X;` (a last, empty column): accepted, as long as
    nothing is in it. An instant outside the run is pointed at in its own cell,
    wherever the TIME column is."""
    model = amilpy.loads(DECAY.replace("PARAM K = (1.0, 2.0)", "PARAM K = 1.0"))
    runs = model.run(data=_write(tmp_path, "TIME;X;\n0,5;0,6;\n"))
    assert list(runs[0].observed[0].t) == [0.5]
    with pytest.raises(AmilError, match="a value in a column with no name") as err:
        model.run(data=_write(tmp_path, "TIME;X;\n0,5;0,6;7\n", "filled.csv"))
    assert (err.value.line, err.value.column) == (2, 9)
    with pytest.raises(AmilError, match="TIME 7.5 is outside run 1") as err:
        model.run(data=_write(tmp_path, "X,TIME\n0.5,7.5\n", "late.csv"))
    assert (err.value.line, err.value.column) == (2, 5)
