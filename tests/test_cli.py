"""The command line: exit codes, printout, files, overrides."""

import os

import pytest

from amilpy.cli import main

DECAY = """TITLE DECAY
PARAM K = 2.0
X = INTGRL(1.0, -K*X)
TIMER FINTIM = 1.0, PRDEL = 0.5, OUTDEL = 0.1
PRINT X
OUTPUT X
LABEL X AGAINST TIME
RANGE X
PREPARE X
END
STOP
"""


@pytest.fixture
def model(tmp_path):
    path = tmp_path / "decay.amil"
    path.write_text(DECAY)
    return path


def test_run_prints_the_lab_table(model, capsys):
    assert main(["run", str(model)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("DECAY\nRUN   (METHOD AUTO")
    lines = out.splitlines()
    head = lines.index("          TIME             X")
    assert lines[head + 1].split() == ["0.000000E+00", "1.000000E+00"]
    assert lines[head + 3].split()[0] == "1.000000E+00"
    assert "RANGE" in out and "MINIMUM" in out
    assert os.path.exists(model.parent / "decay.csv")  # PREPARE


def test_set_overrides_and_csv(model, tmp_path, capsys):
    csv = tmp_path / "out" / "x.csv"
    assert main(["run", str(model), "--set", "K=1.0", "--csv", str(csv), "--quiet"]) == 0
    assert capsys.readouterr().out == ""
    rows = csv.read_text().splitlines()
    assert rows[0] == "TIME,X"
    assert len(rows) == 12
    t, x = map(float, rows[-1].split(","))
    assert t == 1.0 and x == pytest.approx(0.36787944, rel=1e-5)


def test_plot_writes_png(model, tmp_path):
    out = tmp_path / "figs"
    assert main(["run", str(model), "--plot", "--out", str(out), "--quiet"]) == 0
    png = out / "decay.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_written_files_get_the_usual_mode(model, tmp_path):
    """Files are written to a private temporary file and renamed: the CSV and PNG must
    still come out as a plain open() would make them (they were 0600), and an
    existing file keeps its mode."""
    umask = os.umask(0o022)
    try:
        out = tmp_path / "figs"
        assert main(["run", str(model), "--plot", "--out", str(out), "--quiet"]) == 0
        assert (out / "decay.png").stat().st_mode & 0o777 == 0o644
        assert (out / "decay.csv").stat().st_mode & 0o777 == 0o644
        os.chmod(out / "decay.png", 0o640)
        assert main(["run", str(model), "--plot", "--out", str(out), "--quiet"]) == 0
        assert (out / "decay.png").stat().st_mode & 0o777 == 0o640
    finally:
        os.umask(umask)


def test_show_python(model, capsys):
    assert main(["run", str(model), "--show-python", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "def rhs(t, y, m, z):" in out and "-2.0 * v_X" in out


def test_check_ok_and_model_error_exit_codes(tmp_path, capsys):
    good = tmp_path / "g.amil"
    good.write_text(DECAY)
    assert main(["check", str(good)]) == 0
    bad = tmp_path / "b.amil"
    bad.write_text("X = INTGRL(1.0, -KK*X)\nTIMER FINTIM = 1.0\n")
    assert main(["check", str(bad)]) == 1
    err = capsys.readouterr().err
    assert f"{bad}:1:18: error: KK is used but never defined" in err
    assert "Traceback" not in err


@pytest.mark.parametrize("argv", [
    ["run"], ["frobnicate", "x.amil"], ["run", "x.amil", "--rtol", "abc"],
])
def test_usage_errors_exit_2(argv, capsys):
    assert main(argv) == 2


def test_bad_set_is_a_usage_error(model, capsys):
    assert main(["run", str(model), "--set", "K"]) == 2
    assert main(["run", str(model), "--set", "K=abc"]) == 2


def test_unknown_set_name_is_a_usage_error(model, capsys):
    # a name on the command line that the listing does not have is the command
    # line's mistake, not the listing's: exit 2, with the file and a hint
    assert main(["run", str(model), "--set", "KK=1"]) == 2
    err = capsys.readouterr().err
    assert f"amilpy: {model}: --set KK:" in err and "did you mean K?" in err


def test_missing_file(tmp_path, capsys):
    assert main(["run", str(tmp_path / "nope.amil")]) == 1
    assert "cannot read" in capsys.readouterr().err


def test_failed_integration_exits_3_and_keeps_rows(tmp_path, capsys):
    path = tmp_path / "blow.amil"
    path.write_text("X = INTGRL(1.0, X*X)\nTIMER FINTIM = 2.0, OUTDEL = 0.1\nPRINT X\n"
                    "PREPARE X\nEND\n")
    assert main(["run", str(path)]) == 3
    captured = capsys.readouterr()
    assert "PARTIAL RESULTS" in captured.out and "integration failed at TIME = " in captured.err
    # the exact solution 1/(1 - t) blows up at t = 1: rows up to 0.9 are kept
    rows = (tmp_path / "blow.csv").read_text().splitlines()
    assert rows[0].startswith("# PARTIAL (run 1): integration failed at TIME = ")
    assert rows[1] == "TIME,X"
    assert rows[11].startswith("0.9,")
    t_stop = float(rows[-1].split(",")[0])
    assert 0.99 < t_stop <= 1.0


def test_invalid_utf8(tmp_path, capsys):
    path = tmp_path / "bin.amil"
    path.write_bytes(b"X = 1.0\nY = \xff\xfe\n")
    assert main(["check", str(path)]) == 1
    assert ":2:5: error: the file is not valid UTF-8" in capsys.readouterr().err


def test_ctrl_c_keeps_the_rows_and_exits_3(tmp_path, capsys, monkeypatch):
    # Ctrl-C in the middle of a run: the rows so far are printed and written,
    # marked partial, and no further run starts
    import amilpy.cli as cli

    path = tmp_path / "long.amil"
    path.write_text("PARAM K = (1.0, 2.0)\nX = INTGRL(0.0, COS(K*TIME))\n"
                    "TIMER FINTIM = 100.0, OUTDEL = 0.01\nPRINT X\nPREPARE X\nEND\n")

    class Interrupt:
        def __init__(self, enabled):
            pass

        def __call__(self, t, fintim, events, steps):
            if t > 10.0:
                raise KeyboardInterrupt

        def done(self):
            pass

    monkeypatch.setattr(cli, "Progress", Interrupt)
    assert main(["run", str(path), "--method", "RKS"]) == 3
    out = capsys.readouterr()
    assert "interrupted at TIME = " in out.err and "PARTIAL RESULTS" in out.out
    rows = (tmp_path / "long.csv").read_text().splitlines()
    assert rows[0].startswith("# PARTIAL (run 1): interrupted at TIME = ")
    assert rows[1] == "TIME,X" and len(rows) > 500  # one run only, cut after TIME 10
