"""Figures: what each one shows is read back from the matplotlib objects (the data
of every line, the axes, legends and labels), so each test can fail on a wrong
curve, not only on a missing file. The PNGs were looked at as images too."""

import dataclasses
import os
import resource
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT

import amilpy
from amilpy.cli import main
from amilpy.output.options import PlotOptions
from amilpy.output.plot import FigureSpec, draw, figure_specs, plot_figures, zoom_window
from amilpy.output.words import name_notes

OSCILLATOR = """TITLE DAMPED OSCILLATOR
PARAM D = {d}
X = INTGRL(1.0, V)            ! [m] displacement
V = INTGRL(0.0, -X - D*V)     ! [m/s] speed
A = 1000.0*X
TIMER FINTIM = 10.0, OUTDEL = 0.01
OUTPUT X, V
LABEL DISPLACEMENT AND SPEED
OUTPUT X, A
LABEL TWO SCALES
END
"""


def test_one_axis_for_comparable_scales_one_each_beyond_100x():
    model = amilpy.loads(OSCILLATOR.format(d=0.2))
    runs = model.run()
    same, apart = figure_specs(runs[0])
    assert len(draw(runs, same).axes) == 1
    fig = draw(runs, apart, notes=name_notes(model.ir))  # A = 1000 X
    assert len(fig.axes) == 2
    assert [ax.get_ylabel() for ax in fig.axes] == ["X [m]", "A"]
    assert len(draw(runs, same, subplots=True).axes) == 2  # --subplots


def test_curves_are_the_runs_values_with_time_in_seconds():
    run, = amilpy.loads(OSCILLATOR.format(d=0.2)).run()
    fig = draw([run], figure_specs(run)[0], notes=name_notes(amilpy.loads(
        OSCILLATOR.format(d=0.2)).ir))
    ax, = fig.axes
    x_line, v_line = ax.get_lines()
    assert np.array_equal(x_line.get_xdata(), run.t)
    assert np.array_equal(x_line.get_ydata(), run["X"])
    assert np.array_equal(v_line.get_ydata(), run["V"])
    assert x_line.get_linestyle() != v_line.get_linestyle()  # a style per variable
    assert ax.get_xlabel() == "TIME [s]"
    assert ax.get_title() == "DISPLACEMENT AND SPEED"
    # the comments give [m] and [m/s]: no one unit for the axis, so none is claimed
    assert ax.get_ylabel() == "X, V"


def test_label_unit_goes_on_the_y_axis():
    run, = amilpy.loads(OSCILLATOR.format(d=0.2).replace("LABEL DISPLACEMENT AND SPEED",
                                                         "LABEL MOTION [SI]")).run()
    assert draw([run], figure_specs(run)[0]).axes[0].get_ylabel() == "X, V [SI]"


def test_runs_have_a_colour_each_and_a_legend_of_their_values():
    text = OSCILLATOR.format(d=0.2) + "PARAM D = 0.5\nEND\nPARAM D = 1.0\nEND\n"
    runs = amilpy.loads(text).run()
    assert [r.label for r in runs] == ["RUN 1", "D = 0.5", "D = 1"]
    fig = draw(runs, figure_specs(runs[0])[0])
    ax, = fig.axes
    lines = ax.get_lines()
    colours = {}
    for line in lines:
        name, label = line.get_label().split(", ")
        colours.setdefault(label, set()).add(line.get_color())
    # one colour per run, never shared; run 1 is named by its value, not "RUN 1"
    assert set(colours) == {"D = 0.2", "D = 0.5", "D = 1"}
    assert all(len(c) == 1 for c in colours.values())
    assert len({c.pop() for c in colours.values()}) == 3
    texts = [[t.get_text() for t in legend.get_texts()] for legend in
             [*ax.artists, ax.get_legend()] if hasattr(legend, "get_texts")]
    assert ["D = 0.2", "D = 0.5", "D = 1"] in texts and ["X", "V"] in texts


def test_runs_option_keeps_labels_and_colours(tmp_path):
    text = OSCILLATOR.format(d=0.2) + "PARAM D = 0.5\nEND\nPARAM D = 1.0\nEND\n"
    model = amilpy.loads(text)
    runs = model.run()
    drawn = plot_figures(runs, str(tmp_path), "osc", PlotOptions(runs=(1, 3)))
    assert [os.path.basename(f.paths[0]) for f in drawn] == ["osc_1.png", "osc_2.png"]
    assert drawn[0].caption.endswith("; D = 0.2; D = 1")  # the caption names the runs shown
    fig = draw([runs[0], runs[2]], figure_specs(runs[0])[0], ["D = 0.2", "D = 1"],
               numbers=[1, 3])
    colours = {line.get_color() for line in fig.axes[0].get_lines()
               if line.get_label().endswith("D = 1")}
    assert colours == {"C2"}  # run 3 keeps the colour it has among all three


def test_time_window_limits_axes_and_data():
    run, = amilpy.loads(OSCILLATOR.format(d=0.2)).run()
    spec = dataclasses.replace(figure_specs(run)[0], window=(2.0, 3.0))
    ax, = draw([run], spec).axes
    assert ax.get_xlim() == (2.0, 3.0)
    t = ax.get_lines()[0].get_xdata()
    # one instant each side of the window so the line reaches its edges
    assert t[0] == pytest.approx(1.99) and t[-1] == pytest.approx(3.01)
    ylo, yhi = ax.get_ylim()  # scaled to what is inside the window, not the whole run
    inside = run["X"][(run.t >= 1.99) & (run.t <= 3.01)]
    assert yhi - ylo < 1.5 * (max(run["V"].max(), inside.max()) - min(run["V"].min(),
                                                                     inside.min()))


def test_xy_plot_against_a_variable():
    run, = amilpy.loads(OSCILLATOR.format(d=0.2)).run()
    spec = FigureSpec(("V",), "PHASE PLANE", x="X")
    ax, = draw([run], spec, notes={"X": ("m", "")}).axes
    line, = ax.get_lines()
    assert np.array_equal(line.get_xdata(), run["X"]) and np.array_equal(line.get_ydata(),
                                                                         run["V"])
    assert ax.get_xlabel() == "X [m]"


def test_output_vs_builds_an_xy_figure():
    # ir.Report.x (OUTPUT V VS X) as the front end fills it
    run, = amilpy.loads(OSCILLATOR.format(d=0.2)).run()
    run.reports = [dataclasses.replace(r, x="X") if r.kind == "OUTPUT" else r
                   for r in run.reports]
    spec = figure_specs(run)[0]
    assert spec.x == "X"
    assert draw([run], spec).axes[0].get_xlabel() == "X"


CLUTCH = f"{ROOT}/models/ex4_clutch.amil"


def test_zoom_window_is_around_the_engagement_not_the_start_up():
    run, = amilpy.load(CLUTCH).run()
    t1 = run.constants["T1"]
    a, b = zoom_window(run)
    # the friction lets go at 0.27 us (start-up); the clutch engages at T1 and the
    # rotor reverses twice within 0.6 ms: the window starts just before T1
    assert a < t1 < a + 0.2 * (b - a)
    assert b - t1 > 4 * 0.56e-3


def test_zoom_events_writes_a_figure_per_output_group(tmp_path):
    assert main(["run", CLUTCH, "--plot", "--zoom-events", "--out", str(tmp_path),
                 "--quiet"]) == 0
    assert sorted(os.listdir(tmp_path)) == ["ex4_clutch_1.png", "ex4_clutch_1_zoom.png",
                                            "ex4_clutch_2.png", "ex4_clutch_2_zoom.png"]


def test_from_to_window_on_the_command_line(tmp_path):
    assert main(["run", CLUTCH, "--plot", "--from", "0.03", "--to", "0.04", "--out",
                 str(tmp_path), "--quiet"]) == 0
    assert main(["run", CLUTCH, "--plot", "--from", "0.04", "--to", "0.03", "--quiet"]) == 2


def test_failed_run_is_drawn_normally_with_a_small_note():
    run, = amilpy.loads("X = INTGRL(1.0, X*X)\nY = INTGRL(0.0, 1.0)\n"
                        "TIMER FINTIM = 2.0, OUTDEL = 0.01\nOUTPUT Y\nEND\n").run()
    assert not run.ok
    fig = draw([run], figure_specs(run)[0])
    ax, = fig.axes
    notes = [t.get_text() for t in fig.texts]
    assert notes == [f"partial: TIME = {run.t_end:.6g}"]
    assert ax.get_position().height > 0.7  # the axes are not squashed by the note
    assert np.array_equal(ax.get_lines()[0].get_ydata(), run["Y"])


def test_long_title_is_shortened_in_the_plot_only():
    title = "Ж" * 500 + " " + "ω" * 30_000
    run, = amilpy.loads(f"TITLE {title}\nX = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\nEND\n").run()
    ax, = draw([run], figure_specs(run)[0]).axes
    assert len(ax.get_title()) <= 90 and ax.get_title().endswith("…")
    assert run.titles[0] == title  # the printout and report keep it whole


def _vm_peak_mb(argv: list[str], limit_mb: int | None = None) -> tuple[int, int, str]:
    """Run the CLI in a subprocess (under an address-space limit if given); return
    its exit code, its peak address space in MB and its stderr."""
    code = ("import sys; from amilpy.cli import main; rc = main(sys.argv[1:]); "
            "peak = [l for l in open('/proc/self/status') if l.startswith('VmPeak')][0]; "
            "print(int(peak.split()[1]) // 1024); sys.exit(rc)")

    def cap():
        if limit_mb:
            resource.setrlimit(resource.RLIMIT_AS, (limit_mb * 2**20, limit_mb * 2**20))

    env = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
    done = subprocess.run([sys.executable, "-c", code, *argv], preexec_fn=cap, env=env,
                          capture_output=True, timeout=300, text=True)
    lines = done.stdout.split()
    return done.returncode, int(lines[-1]) if lines else -1, done.stderr


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and RLIMIT_AS")
def test_long_title_plot_fits_in_little_memory(tmp_path):
    """--plot with a 30 000-character non-Latin TITLE took 1.9 GB in matplotlib's
    layout (here, with CJK glyphs missing from the font, 360 MB and 90 s). With the
    title shortened in the plot it needs no more address space than a short title,
    give or take 150 MB: that is the limit it runs under."""
    short = tmp_path / "short.amil"
    short.write_text("TITLE SHORT\nX = INTGRL(1.0, -X)\nTIMER FINTIM = 1.0\nOUTPUT X\nEND\n")
    code, baseline, err = _vm_peak_mb(["run", str(short), "--plot", "--quiet"])
    assert code == 0 and baseline > 0, err
    long = tmp_path / "long.amil"
    long.write_text("TITLE " + "中" * 30_000 + "\nX = INTGRL(1.0, -X)\n"
                    "TIMER FINTIM = 1.0\nOUTPUT X\nEND\n", encoding="utf-8")
    code, peak, err = _vm_peak_mb(["run", str(long), "--plot", "--quiet"], baseline + 150)
    assert code == 0, err[-2000:]
    assert (tmp_path / "long.png").exists()


def test_the_time_axis_says_the_form_s_unit(tmp_path):
    """TIME [s] in the CSMP form (the lab's mechanics); an ACSL program (a
    pharmacokinetic one counts hours) says none; an FST listing days. The shipped
    oral-dosing figure said seconds for its hours."""
    import amilpy
    from amilpy.output.plot import _x_label, figure_specs
    from amilpy.output.words import name_notes

    csmp = amilpy.loads("X = INTGRL(0.0, 1.0)\nTIMER FINTIM = 1.0\nOUTPUT X\nEND\n")
    acsl = amilpy.load(os.path.join(ROOT, "models", "examples", "oral_dosing.csl"))
    fst = amilpy.load(os.path.join(ROOT, "models", "examples", "fst_wheat.fst"))
    labels = []
    for model in (csmp, acsl, fst):
        spec = figure_specs(model.run(advice=False)[0])[0]
        labels.append(_x_label(spec, name_notes(model.ir)))
    assert labels == ["TIME [s]", "TIME", "TIME [d]"]


BALL = """TITLE A BOUNCING BALL
V = INTGRL(0.0, -9.81)
H = INTGRL(1.0, V)
EVENT
ZEROCONDITION H
NEWVALUE V = -0.8*V
NEWVALUE H = 0.0
ENDEVENT
TIMER FINTIM = 1.0, OUTDEL = 0.1
OUTPUT H
END
"""


def test_a_figure_draws_the_instants_between_grid_rows_where_the_ball_lands():
    # the impact at t = sqrt(2/9.81) = 0.4515 s lies between the OUTDEL rows 0.4 and 0.5:
    # the line touches the floor there, as the located event says, not at 0.16 m (the
    # grid's lowest row), which the figure drew before
    run, = amilpy.loads(BALL, "ball.fst").run(advice=False)
    line, = draw([run], figure_specs(run)[0]).axes[0].get_lines()
    t, h = line.get_xdata(), line.get_ydata()
    impact = np.sqrt(2.0 / 9.81)
    k = int(np.argmin(np.abs(t - impact)))
    assert t[k] == pytest.approx(impact, abs=1e-9) and abs(h[k]) < 1e-9
    assert min(run["H"]) > 0.15  # (the grid alone never comes near the floor)
    assert set(run.t) <= set(t)
