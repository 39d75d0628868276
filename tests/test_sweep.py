"""`amilpy sweep` / `Model.sweep`: the hoist's amplitude-frequency characteristic
with its jump, against the plain-SciPy reference sweep of tests/references/hoist.py."""

import numpy as np
import pytest
from conftest import ROOT
from references import hoist

import amilpy
from amilpy.cli import main
from amilpy.sweep import parse_range

MODEL = f"{ROOT}/models/hoist_backlash.amil"
H = hoist.Hoist()
# the loaded equilibrium (teeth in contact, shaft wound up by MN): the start of a sweep
EQ = {"X10": H.mn / H.c1, "Y0": H.half_gap + H.mn / H.c2}


def test_parse_range():
    assert parse_range("w=1:2:0.25") == ("W", [1.0, 1.25, 1.5, 1.75, 2.0])
    assert parse_range("W=3:1:-1") == ("W", [3.0, 2.0, 1.0])
    for bad in ("W=1:2", "W=1:2:0", "W=2:1:0.5", "W"):
        with pytest.raises(amilpy.AmilError):
            parse_range(bad)


@pytest.mark.slow  # (about 16 s on this machine)
def test_hoist_sweep_matches_reference_and_shows_hysteresis():
    # up across the upper fold (72.05 rad/s by damped harmonic balance) and back down;
    # 10 s a point, measured over the last 3 s, TIME and the state carried on.
    ws = [70.0, 71.0, 71.8, 72.4]
    model = amilpy.load(MODEL)
    result = model.sweep("W", ws, both_ways=True, carry_state=True, settle=7.0, fintim=10.0,
                         measure="Y", rtol=1e-9, atol=1e-12, **EQ)
    up_w, up_a = result.branch("up")
    down_w, down_a = result.branch("down")
    assert list(up_w) == ws and list(down_w) == ws[-2::-1]
    a = np.concatenate([up_a, down_a])
    separation = H.mn / H.c2  # the amplitude at which the teeth leave each other
    assert max(up_a[:3]) < separation < up_a[3]  # jumped up past the fold ...
    assert down_a[-1] > 4 * up_a[0]  # ... and stays up coming back: hysteresis at 70
    # amilpy locates each window's extrema between its 1 ms rows; the reference
    # samples Y every 20 us, which puts its peaks within (72 rad/s * 20 us)**2/8 =
    # 3e-7 of the true ones (the 1 ms rows alone are low by up to 6e-4). Both
    # integrate at rtol 1e-9; 1e-5 is what the carried states' differences allow.
    ref, _ = hoist.sweep(H, ws + ws[-2::-1], 7.0, 3.0, y0=np.array(
        [EQ["X10"], EQ["Y0"], 0, 0, 0, 0]), rtol=1e-9, dt_sample=2e-5)
    assert np.allclose(a, ref, rtol=1e-5)


def test_sweep_command_writes_table_csv_and_plot(tmp_path, capsys):
    csv = tmp_path / "s.csv"
    code = main(["sweep", MODEL, "W=60:62:1", "--fintim", "1.0", "--settle", "0.5",
                 "--measure", "Y", "--csv", str(csv), "--plot", "--out", str(tmp_path)])
    assert code == 0
    out = capsys.readouterr().out
    assert out.startswith("SWEEP OF W, Y MEASURED AFTER 0.5 S")
    rows = csv.read_text().splitlines()
    assert rows[0].startswith("DIRECTION,W,MIN_Y,MAX_Y,HALF_PP_Y")
    assert [r.split(",")[1] for r in rows[1:]] == ["60.0", "61.0", "62.0"]
    assert (tmp_path / "hoist_backlash_sweep.png").read_bytes()[:4] == b"\x89PNG"


def test_carried_state_continues_time_and_phase():
    text = ("PARAM W = 1.0\nPH = INTGRL(0.0, W)\nX = SIN(PH)\nY = STEP(1.5)\n"
            "TIMER FINTIM = 1.0, OUTDEL = 0.5\nEND\n")
    result = amilpy.loads(text).sweep("W", [1.0, 2.0], carry_state=True, keep_runs=True)
    first, second = result.runs
    assert list(second.t) == [1.0, 1.5, 2.0]  # TIME goes on
    assert second["PH"][0] == pytest.approx(first["PH"][-1])  # the phase is continuous
    assert second["PH"][-1] == pytest.approx(1.0 + 2.0, rel=1e-6)
    assert list(second["Y"]) == [0.0, 1.0, 1.0]  # STEP(1.5) happens in the second run


# ----------------------------------------------------------------- jumps


def _sweep(values, amplitudes, directions=None, carry_state=False):
    from amilpy.sweep import Sweep, SweepPoint

    result = Sweep("W", "Y", 0.0, carry_state=carry_state)
    directions = directions or ["up"] * len(values)
    for v, a, d in zip(values, amplitudes, directions, strict=True):
        result.points.append(SweepPoint(v, d, -a, a, "finished", 0.0, 1.0))
    return result


def test_no_jump_on_a_monotonic_characteristic():
    # W=70:71:0.5 once reported "largest rise sweeping up: between 70.5 and 71" while
    # the amplitude fell; a smooth fall, however steep, is not a jump
    assert _sweep([70.0, 70.5, 71.0], [0.010, 0.008, 0.0055]).jumps() == {"up": None}
    w = np.linspace(60, 80, 41)
    assert _sweep(list(w), list(np.exp(-(w - 60) / 3))).jumps() == {"up": None}


def test_a_jump_is_found_with_its_sign_where_it_stands_out():
    rng = np.random.default_rng(1)
    w = np.arange(66.0, 75.01, 0.5)
    a = 0.004 + 0.0002 * (w - 66) + 1e-5 * rng.standard_normal(len(w))
    a[w > 72.0] += 0.02  # the fold: up onto the large branch between 72 and 72.5
    up = _sweep(list(w), list(a)).jumps()["up"]
    assert (up.start, up.stop, up.rise) == (72.0, 72.5, True) and up.ratio > 20
    down = _sweep(list(w[::-1]), list(a[::-1]), ["down"] * len(w)).jumps()["down"]
    assert (down.start, down.stop, down.rise) == (72.5, 72.0, False)


def test_the_first_point_of_a_carried_sweep_is_left_out():
    # the first run starts from the listing's state: its amplitude is a transient's
    values = [70.0, 70.5, 71.0, 71.5, 72.0]
    amplitudes = [0.05, 0.010, 0.0101, 0.0102, 0.0103]
    assert _sweep(values, amplitudes).jumps()["up"].stop == 70.5
    assert _sweep(values, amplitudes, carry_state=True).jumps() == {"up": None}
    from amilpy.output.sweeps import jump_lines

    lines = jump_lines(_sweep(values, amplitudes, carry_state=True))
    assert lines[0].startswith("the first point (W = 70) starts from the listing's initial "
                               "state, a transient: it is left out of the jump search")
    assert lines[1].startswith("no jump sweeping up")


def test_sweep_plot_has_units_on_both_axes(tmp_path):
    from amilpy.output.sweeps import plot_sweep

    result = _sweep([1.0, 2.0, 3.0], [0.1, 0.2, 0.3])
    path = plot_sweep(result, str(tmp_path / "s.png"), axis_units=("rad/s", "RAD"))
    assert open(path, "rb").read(4) == b"\x89PNG"
    from amilpy.output.sweeps import units

    model = amilpy.loads("PARAM W = 1.0   ! [rad/s] excitation frequency\n"
                         "Y = INTGRL(0.0, SIN(W*TIME))\nTIMER FINTIM = 1.0\nOUTPUT Y\n"
                         "LABEL TWIST [RAD]\nEND\n")
    assert units(model, result) == ("rad/s", "RAD")


def test_sweep_extrema_are_located_between_coarse_rows():
    # X'' + 2 Z X' + X = COS(W*TIME): the steady amplitude is 1/sqrt((1 - W^2)^2 +
    # (2 Z W)^2). Rows every 0.7 s (about 9 a period) miss the peak by up to 6 %;
    # the sweep's MAX and MIN are located on the integrator's dense output. After
    # 90 s the transient is e^(-0.2*90) = 1.5e-8 of its start.
    model = amilpy.loads("PARAM W = 1.0, Z = 0.2\nX = INTGRL(0.0, V)\n"
                         "V = INTGRL(0.0, COS(W*TIME) - 2.0*Z*V - X)\n"
                         "TIMER FINTIM = 100.0, OUTDEL = 0.7\nRELERR 1.0E-10\n"
                         "ABSERR 1.0E-12\nEND\n")
    ws = [0.8, 1.0, 1.3]
    result = model.sweep("W", ws, settle=90.0, measure="X")
    for w, p in zip(ws, result.points, strict=True):
        exact = 1.0 / np.hypot(1.0 - w * w, 0.4 * w)
        assert p.maximum == pytest.approx(exact, rel=1e-6)
        assert p.minimum == pytest.approx(-exact, rel=1e-6)
