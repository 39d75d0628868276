"""What a student takes out of a run for the report: every PRINT and OUTPUT
variable in the CSV and workbook (or the ones named with --vars), figures as PNG,
SVG or PDF, a windowed figure beside the whole run's, and two listings overlaid."""

import csv
import math
import re
import zipfile

import pytest

from amilpy.cli import main

# X and V are printed; E is only plotted, against X; PHASE only plotted against TIME.
# The closed form: X = cos(t), V = -sin(t), E = (X^2 + V^2)/2 = 1/2.
OSCILLATOR = """TITLE HARMONIC OSCILLATOR
PARAM W = 1.0   ! [rad/s] natural frequency
X = INTGRL(1.0, V)
V = INTGRL(0.0, -W*W*X)
E = 0.5*(X*X + V*V/(W*W))
PHASE = ATAN2(-V, X)
TIMER FINTIM = 6.0, OUTDEL = 0.5, PRDEL = 1.0
PRINT X, V
OUTPUT E VS X
LABEL ENERGY [J]
OUTPUT PHASE
END
"""


def _write(tmp_path, name, text=OSCILLATOR):
    path = tmp_path / f"{name}.amil"
    path.write_text(text)
    return path


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.reader(line for line in fh if not line.startswith("#")))


def test_csv_carries_every_print_and_output_variable(tmp_path):
    model = _write(tmp_path, "osc")
    assert main(["run", str(model), "--quiet", "--csv", str(tmp_path / "o.csv")]) == 0
    rows = _rows(tmp_path / "o.csv")
    # PRINT's first, then each OUTPUT's (its X included), once each
    assert rows[0] == ["TIME", "X", "V", "E", "PHASE"]
    assert len(rows) == 1 + 13  # OUTDEL 0.5 over 6 s
    for row in rows[1:]:
        t, x, v, e, phase = map(float, row)
        # default tolerances: the printed digits of a 6-digit printout, with margin
        assert x == pytest.approx(math.cos(t), abs=1e-7)
        assert v == pytest.approx(-math.sin(t), abs=1e-7)
        assert e == pytest.approx(0.5, abs=1e-7)
        assert math.cos(phase) == pytest.approx(math.cos(t), abs=1e-7)


def test_vars_chooses_the_columns_data_values_included(tmp_path, capsys):
    model = _write(tmp_path, "osc")
    out = tmp_path / "v.csv"
    assert main(["run", str(model), "--quiet", "--csv", str(out), "--vars", "phase,W"]) == 0
    rows = _rows(out)
    assert rows[0] == ["TIME", "PHASE", "W"]
    assert {float(r[2]) for r in rows[1:]} == {1.0}  # a data value: its value each row
    # a name the listing does not have: a usage error with the nearest name
    assert main(["run", str(model), "--quiet", "--csv", str(out), "--vars", "PHASE,EE"]) == 2
    err = capsys.readouterr().err
    assert "EE is not a variable or data value of the model" in err and "E" in err


def test_xlsx_carries_the_same_columns(tmp_path):
    pytest.importorskip("xlsxwriter")
    model = _write(tmp_path, "osc")
    path = tmp_path / "o.xlsx"
    assert main(["run", str(model), "--quiet", "--xlsx", str(path)]) == 0
    with zipfile.ZipFile(path) as z:
        names = z.read("xl/sharedStrings.xml").decode() if "xl/sharedStrings.xml" in \
            z.namelist() else z.read("xl/worksheets/sheet1.xml").decode()
    for column in ("TIME", "X", "V", "E", "PHASE"):
        assert f">{column}<" in names


def test_figures_in_every_format_asked_for(tmp_path):
    model = _write(tmp_path, "osc")
    assert main(["run", str(model), "--quiet", "--format", "png,svg,pdf"]) == 0
    for k in (1, 2, 3):  # one figure per OUTPUT... and PRINT makes none: two here
        stem = tmp_path / f"osc_{k}"
        if k == 3:
            assert not stem.with_suffix(".png").exists()
            continue
        assert stem.with_suffix(".png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert stem.with_suffix(".pdf").read_bytes()[:5] == b"%PDF-"
        svg = stem.with_suffix(".svg").read_text()
        assert svg.lstrip().startswith("<?xml") and "<svg" in svg
    # SVG keeps its text as text: the axis labels can be searched (and restyled)
    assert "ENERGY" in (tmp_path / "osc_1.svg").read_text()
    assert "E [J]" in (tmp_path / "osc_1.svg").read_text()
    assert "X" in (tmp_path / "osc_1.svg").read_text()
    # the same figure drawn twice is the same file (no date inside)
    first = (tmp_path / "osc_1.svg").read_bytes()
    assert main(["run", str(model), "--quiet", "--format", "svg"]) == 0
    assert (tmp_path / "osc_1.svg").read_bytes() == first


def test_a_bad_format_is_a_usage_error(tmp_path, capsys):
    model = _write(tmp_path, "osc")
    assert main(["run", str(model), "--format", "png,jpg"]) == 2
    assert "png,svg,pdf" in capsys.readouterr().err


def test_a_windowed_figure_keeps_the_whole_runs_figure(tmp_path):
    model = _write(tmp_path, "osc")
    assert main(["run", str(model), "--quiet", "--plot"]) == 0
    whole = (tmp_path / "osc_2.png").read_bytes()
    assert main(["run", str(model), "--quiet", "--plot", "--from", "1", "--to", "2.5"]) == 0
    assert (tmp_path / "osc_2.png").read_bytes() == whole
    assert (tmp_path / "osc_2_from_1_to_2.5.png").read_bytes() != whole
    # a window with only one end given is named by both of its ends
    assert main(["run", str(model), "--quiet", "--plot", "--from", "3"]) == 0
    assert (tmp_path / "osc_2_from_3_to_6.png").exists()


def test_two_listings_overlaid_in_one_figure(tmp_path, capsys):
    slow = _write(tmp_path, "slow")
    fast = _write(tmp_path, "fast", OSCILLATOR.replace("W = 1.0", "W = 2.0"))
    code = main(["run", str(slow), str(fast), "--overlay", "--format", "svg", "--quiet"])
    assert code == 0
    made = sorted(p.name for p in tmp_path.iterdir() if p.suffix == ".svg")
    # the overlay replaces each listing's own figures
    assert made == ["slow_vs_fast_1.svg", "slow_vs_fast_2.svg"]
    svg = (tmp_path / "slow_vs_fast_2.svg").read_text()
    # the legend names each listing by its file; PHASE of both, two lines
    assert ">slow<" in svg and ">fast<" in svg
    # (the data lines are drawn 1.2 wide, a colour per run: blue C0, orange C1)
    for colour in ("#1f77b4", "#ff7f0e"):
        assert len(re.findall(f"stroke: {colour}; stroke-width: 1.2", svg)) == 1
    # one listing cannot be overlaid with itself
    assert main(["run", str(slow), "--overlay"]) == 2
    assert "give two or more" in capsys.readouterr().err


def test_overlay_draws_a_variable_only_where_a_listing_has_it(tmp_path):
    from amilpy import loads
    from amilpy.output.options import PlotOptions
    from amilpy.output.plot import plot_overlay

    a = loads(OSCILLATOR).run()
    b = loads(OSCILLATOR.replace("OUTPUT PHASE\n", "").replace("PHASE = ATAN2(-V, X)\n",
                                                                    "")).run()
    paths = plot_overlay([("a", a), ("b", b)], str(tmp_path), PlotOptions(formats=("svg",)))
    assert [p.rsplit("/", 1)[1] for p in paths] == ["a_vs_b_1.svg", "a_vs_b_2.svg"]
    energy, phase = ((tmp_path / f"a_vs_b_{k}.svg").read_text() for k in (1, 2))
    assert len(re.findall("stroke-width: 1.2", energy)) == 2  # both have E
    assert len(re.findall("stroke-width: 1.2", phase)) == 1  # only a has PHASE


@pytest.mark.parametrize("command, extra, stem", [
    ("sweep", ["W=0.5:1.5:0.5", "--fintim", "2"], "osc_sweep"),
    ("periodic", ["--period", "2*PI/W", "--settle", "0"], "osc_periodic")])
def test_sweep_and_analysis_figures_take_the_format_too(tmp_path, command, extra, stem):
    model = _write(tmp_path, "osc")
    code = main([command, str(model), *extra, "--format", "pdf,svg", "--quiet",
                 "--out", str(tmp_path)])
    assert code == 0
    assert (tmp_path / f"{stem}.pdf").read_bytes()[:5] == b"%PDF-"
    assert "<svg" in (tmp_path / f"{stem}.svg").read_text()
    assert not (tmp_path / f"{stem}.png").exists()


def test_overlay_of_an_x_plot_with_a_listing_that_lacks_x(tmp_path):
    # the first listing plots E against X; the second has no X: drawn without it,
    # never a KeyError (a review found the traceback)
    first = _write(tmp_path, "first")
    other = _write(tmp_path, "other", "TITLE OTHER\nE = INTGRL(0.5, 0.0)\nPHASE = E\n"
                                      "TIMER FINTIM = 6.0, OUTDEL = 0.5\nOUTPUT E\nEND\n")
    assert main(["run", str(first), str(other), "--overlay", "--format", "svg",
                 "--quiet"]) == 0
    energy = (tmp_path / "first_vs_other_1.svg").read_text()
    assert len(re.findall("stroke-width: 1.2", energy)) == 1  # first's E against X only


def test_a_listing_name_with_dots_keeps_them_in_its_figures(tmp_path):
    model = _write(tmp_path, "lab.svg")
    assert main(["run", str(model), "--quiet", "--plot"]) == 0
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["lab.svg_1.png", "lab.svg_2.png"]
    assert main(["sweep", str(model), "W=0.5:1.5:0.5", "--fintim", "2", "--plot", "--quiet",
                 "--out", str(tmp_path)]) == 0
    assert (tmp_path / "lab.svg_sweep.png").exists() and not (tmp_path / "lab.png").exists()


def test_vars_may_name_time(tmp_path):
    model = _write(tmp_path, "osc")
    out = tmp_path / "t.csv"
    assert main(["run", str(model), "--quiet", "--csv", str(out), "--vars", "TIME,X"]) == 0
    assert _rows(out)[0] == ["TIME", "X"]
