"""`amilpy modes`, `periodic` and `response` from the command line: what they
print and write, their exit codes and usage errors."""

import csv
import math

import pytest

from amilpy.cli import main

OSCILLATOR = """TITLE FORCED OSCILLATOR
PARAM W = 1.5, W0 = 2.0, Z = 0.05, F = 1.0   ! [RAD/S] forcing frequency
X = INTGRL(0.0, V)
V = INTGRL(0.0, F*SIN(W*TIME) - 2.0*Z*W0*V - W0*W0*X)
TIMER FINTIM = 60.0, OUTDEL = 0.1
OUTPUT X
LABEL DISPLACEMENT [M]
END
"""


@pytest.fixture
def model(tmp_path):
    path = tmp_path / "osc.amil"
    path.write_text(OSCILLATOR)
    return path


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.reader(line for line in fh if not line.startswith("#")))


def test_modes_prints_the_table_and_writes_csv(model, tmp_path, capsys):
    out_csv = tmp_path / "m.csv"
    assert main(["modes", str(model), "--csv", str(out_csv)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("LINEAR MODES OF FORCED OSCILLATOR")
    assert "MODE SHAPES" in out
    rows = _rows(out_csv)
    assert rows[0] == ["RE", "IM", "WN", "FHZ", "ZETA", "V", "X", "IM_V", "IM_X"]
    re, im, wn, fhz, zeta = map(float, rows[1][:5])
    assert wn == pytest.approx(2.0, rel=1e-12) and zeta == pytest.approx(0.05, rel=1e-12)
    assert fhz == pytest.approx(2.0 / (2 * math.pi), rel=1e-12)


def test_periodic_writes_csv_and_png(model, tmp_path, capsys):
    out_csv = tmp_path / "p.csv"
    code = main(["periodic", str(model), "--period", "2*PI/W", "--measure", "X",
                 "--measure", "v", "--csv", str(out_csv), "--plot", "--out", str(tmp_path)])
    assert code == 0
    out = capsys.readouterr().out
    assert "PERIODIC STEADY STATE" in out and "stable" in out and "period 4.18879" in out
    rows = _rows(out_csv)
    assert rows[0] == ["PERIOD", "MIN_X", "MAX_X", "MEAN_X", "HALF_PP_X", "MIN_V", "MAX_V",
                       "MEAN_V", "HALF_PP_V", "STABLE", "MU_MAX"]
    amplitude = 1.0 / math.sqrt((4 - 2.25) ** 2 + (0.2 * 1.5) ** 2)
    assert float(rows[1][4]) == pytest.approx(amplitude, rel=1e-8)
    assert rows[1][9] == "1"
    png = tmp_path / "osc_periodic.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_response_writes_csv_and_png_quietly(model, tmp_path, capsys):
    out_csv = tmp_path / "r.csv"
    code = main(["response", str(model), "W=1.8:2.2", "--period", "2*PI/W", "--csv",
                 str(out_csv), "--plot", "--out", str(tmp_path), "--quiet"])
    assert code == 0
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""
    rows = _rows(out_csv)
    assert rows[0] == ["W", "PERIOD", "MIN_X", "MAX_X", "HALF_PP_X", "STABLE", "MU_MAX",
                       "KIND"]
    assert float(rows[1][0]) == 1.8 and float(rows[-1][0]) == 2.2 and rows[-1][7] == "end"
    assert (tmp_path / "osc_response.png").read_bytes()[:4] == b"\x89PNG"


def test_no_orbit_is_exit_3_with_the_residual_history(tmp_path, capsys):
    # a phase given a period: it never comes back
    path = tmp_path / "phase.amil"
    path.write_text("PARAM W = 2.0\nPH = INTGRL(0.0, W)\nX = INTGRL(0.0, SIN(PH) - X)\n"
                    "TIMER FINTIM = 5.0\nEND\n")
    assert main(["periodic", str(path), "--period", "2*PI/W"]) == 3
    err = capsys.readouterr().err
    assert "no periodic orbit found" in err and "residual history" in err
    assert "--angle PH=VALUE" in err
    # the same with the angle: found
    assert main(["periodic", str(path), "--angle", "PH=2*PI", "--quiet"]) == 0


@pytest.mark.parametrize("argv, message", [
    (["response", "{m}", "W=1:1", "--period", "1"], "START and STOP must be finite and differ"),
    (["response", "{m}", "W1.0:2.0", "--period", "1"], "NAME=START:STOP"),
    (["response", "{m}", "WW=1:2", "--period", "1"], "did you mean W?"),
    (["periodic", "{m}", "--period", "1", "--measure", "XX"], "did you mean X?"),
    (["periodic", "{m}", "--angle", "PH"], "NAME=VALUE"),
    (["periodic", "{m}"], "one of the arguments --period --angle is required"),
    (["periodic", "{m}", "--period", "1", "--angle", "X=1"], "not allowed with"),
])
def test_usage_errors(model, capsys, argv, message):
    assert main([a.format(m=model) for a in argv]) == 2
    assert message in capsys.readouterr().err


def test_a_bad_period_expression_is_a_model_error(model, capsys):
    assert main(["periodic", str(model), "--period", "2*PI/Q"]) == 1
    assert "Q is not a constant of this listing" in capsys.readouterr().err
