"""`amilpy sweep` / `Model.sweep`: the hoist's amplitude-frequency characteristic
with its jump, against the plain-SciPy reference sweep of tests/references/hoist.py."""

import math
import os

import numpy as np
import pytest
from conftest import ROOT
from references import duffing, hoist

import amilpy
from amilpy.batch.sweep import parse_range
from amilpy.cli import main

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
    assert rows[0] == ("DIRECTION,W,MIN_Y,MAX_Y,HALF_PP_Y,STATUS,TIME_START,TIME_END,"
                       "HALF_PP_DRIFT_Y")
    # each point's drift is the half peak-to-peak's change over its settled window
    assert all(0.0 <= float(r.split(",")[-1]) < 1.0 for r in rows[1:])
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


def _sweep(values, amplitudes, directions=None, carry_state=False, unsteady=None):
    from amilpy.batch.sweep import Sweep, SweepPoint

    result = Sweep("W", "Y", 0.0, carry_state=carry_state)
    directions = directions or ["up"] * len(values)
    unsteady = unsteady if unsteady is not None else [math.nan] * len(values)
    for v, a, d, u in zip(values, amplitudes, directions, unsteady, strict=True):
        result.points.append(SweepPoint(v, d, -a, a, "finished", 0.0, 1.0, unsteady=u))
    return result


def _jumps(result, direction="up"):
    return [(j.start, j.stop, j.rise) for j in result.jumps()[direction]]


def test_no_jump_on_a_smooth_characteristic():
    # W=70:71:0.5 once reported "largest rise sweeping up: between 70.5 and 71" while
    # the amplitude fell; a smooth fall, however steep, is not a jump, nor is a
    # resonance peak sampled 10 points across its width (2 zeta w0 = 0.2)
    assert _sweep([70.0, 70.5, 71.0], [0.010, 0.008, 0.0055]).jumps() == {}  # too few
    w = np.linspace(60, 80, 41)
    assert _sweep(list(w), list(np.exp(-(w - 60) / 3))).jumps() == {"up": []}
    w = np.round(np.arange(1.5, 2.5001, 0.02), 12)
    a = 1.0 / np.sqrt((4.0 - w * w) ** 2 + (2 * 0.05 * 2.0 * w) ** 2)
    assert _sweep(list(w), list(a)).jumps() == {"up": []}
    assert _sweep(list(w[::-1]), list(a[::-1]), ["down"] * len(w)).jumps() == {"down": []}


def test_a_jump_is_found_with_its_sign_where_it_stands_out():
    rng = np.random.default_rng(1)
    w = np.arange(66.0, 75.01, 0.5)
    a = 0.004 + 0.0002 * (w - 66) + 1e-5 * rng.standard_normal(len(w))
    a[w > 72.0] += 0.02  # the fold: up onto the large branch between 72 and 72.5
    up, = _sweep(list(w), list(a)).jumps()["up"]
    assert (up.start, up.stop, up.rise) == (72.0, 72.5, True) and up.ratio > 20
    down = _sweep(list(w[::-1]), list(a[::-1]), ["down"] * len(w))
    assert _jumps(down, "down") == [(72.5, 72.0, False)]
    # the same noise given as each point's unsteadiness: still found, nothing else
    noisy = _sweep(list(w), list(a), unsteady=[1e-5] * len(w))
    assert _jumps(noisy) == [(72.0, 72.5, True)]


def test_points_that_have_not_settled_are_no_jump():
    # a branch whose points scatter by 2e-4 (their orbits not settled): the trend
    # misses them by that much; with each point's unsteadiness (the two halves of
    # its window differ by about as much) no step is a jump
    rng = np.random.default_rng(7)
    w = np.arange(60.0, 70.01, 0.2)
    a = 0.02 + 0.001 * (w - 60) + 2e-4 * rng.standard_normal(len(w))
    assert _jumps(_sweep(list(w), list(a), unsteady=[2e-4] * len(w))) == []


# the docs' hoist sweep (docs/models.md: W=67.5:73:0.1 both ways, state carried, 20 s a
# point, Y measured after 17 s), as amilpy computed it (5 min; regenerate with the
# command in docs/models.md and `Sweep.points`): HALF P-P of Y and each point's
# unsteadiness, sweeping up from 67.5 and down from 72.9
HOIST_UP = [
    0.00233768, 0.002378518, 0.002425486, 0.002474456, 0.002525588, 0.00257895, 0.002634735,
    0.002693154, 0.002754308, 0.002818432, 0.002885753, 0.002956581, 0.003031051, 0.00310953,
    0.003192351, 0.003279959, 0.003372597, 0.003470813, 0.003575213, 0.003686211, 0.003804512,
    0.003930887, 0.004066343, 0.004211511, 0.004367685, 0.004536162, 0.004718612, 0.004916344,
    0.005131636, 0.005367161, 0.00562528, 0.005909549, 0.006224188, 0.006574754, 0.006966167,
    0.00740669, 0.007906061, 0.008476353, 0.00913153, 0.00989199, 0.01078519, 0.01184056,
    0.01310287, 0.01462895, 0.01649108, 0.01875237, 0.0222656, 0.02205637, 0.02183703,
    0.02160521, 0.02135759, 0.02108866, 0.02078791, 0.02042804, 0.01933381, 0.0169179,]
HOIST_UP_UNSTEADY = [
    2.78e-06, 3.55e-08, 2.63e-08, 8.68e-08, 3.93e-08, 3.22e-08, 2.65e-08, 1.31e-08, 4.01e-07,
    2e-10, 5.47e-08, 2.79e-08, 3.82e-08, 3.2e-08, 1.85e-08, 2.82e-09, 5.13e-08, 6.11e-08,
    6.6e-08, 6.54e-08, 7.64e-08, 1.42e-07, 3.01e-08, 1.36e-07, 2.42e-07, 1.04e-07, 1.69e-07,
    2.19e-07, 2.61e-07, 2.09e-07, 5.14e-07, 4.23e-08, 4.68e-07, 7.43e-07, 2.78e-07, 3.86e-07,
    2.03e-07, 9.15e-07, 3.06e-08, 1.24e-06, 2.37e-06, 1.64e-07, 1.75e-06, 1.19e-06, 2.34e-06,
    1.11e-06, 2.17e-07, 6.65e-07, 6.07e-08, 1.09e-08, 1.98e-07, 1.07e-07, 1.77e-07, 5.1e-08,
    1.09e-06, 1.16e-06,]
HOIST_DOWN = [
    0.01933319, 0.02042947, 0.02078803, 0.02108877, 0.02135759, 0.0216052, 0.02183702,
    0.02205637, 0.02226546, 0.02246588, 0.02265878, 0.02284507, 0.02302546, 0.02320056,
    0.02337097, 0.02353728, 0.02370017, 0.02386047, 0.02401912, 0.0241772, 0.02433585,
    0.02449618, 0.02465919, 0.0248258, 0.02499701, 0.02517437, 0.02536015, 0.02555753,
    0.02577105, 0.02600513, 0.02625161, 0.02642869, 0.02651449, 0.02679214, 0.02684508,
    0.02718747, 0.02739017, 0.02754135, 0.02778042, 0.02798917, 0.02837118, 0.02862057,
    0.02875538, 0.02918352, 0.02964916, 0.03023231, 0.03098464, 0.03204671, 0.03410917,
    0.03584222, 0.03487177, 0.01048916, 0.00243146, 0.002378504, 0.002333412,]
HOIST_DOWN_UNSTEADY = [
    2.71e-06, 2.4e-06, 1.7e-07, 2.3e-07, 3.65e-08, 1.14e-08, 4.72e-09, 1.31e-06, 6e-08,
    9.62e-10, 1.24e-08, 1.58e-06, 1.69e-11, 1.05e-07, 7.73e-08, 9.59e-08, 1.32e-07, 9.39e-08,
    1.35e-08, 8.79e-07, 1.45e-08, 1.09e-07, 1.08e-07, 1.3e-07, 4.85e-07, 8.03e-07, 1e-06,
    8.17e-06, 3.93e-05, 0.000123, 0.000199, 7.25e-05, 6.13e-05, 8.13e-05, 1.21e-05, 0.000159,
    0.000214, 9.84e-05, 0.000258, 0.00022, 7.68e-05, 0.000327, 5.94e-05, 3.19e-05, 1.04e-05,
    9.83e-06, 2.26e-08, 3.09e-06, 1.88e-06, 2.36e-06, 1.11e-06, 0.00311, 2.85e-06, 2.89e-08,
    6.1e-09,]


def test_the_docs_hoist_sweep_has_its_two_jumps_and_no_other():
    """The up-jump between 72.0 and 72.1 rad/s (0.01875 -> 0.02227, the damped
    harmonic balance's fold at 72.045) and the down-jump between 67.9 and 67.8
    (67.82), nothing else: not the up-branch bending towards its fold at the sweep's
    end (72.9 -> 73.0, which the old rule reported instead of the up-jump), nor the
    down-branch's points scattering by 2e-4 between 68 and 70 (their windows moved
    by about as much: not settled), nor 67.8, a point caught halfway."""
    up = [round(67.5 + 0.1 * k, 12) for k in range(56)]
    down = up[-2::-1]
    result = _sweep(up + down, HOIST_UP + HOIST_DOWN, ["up"] * 56 + ["down"] * 55,
                    carry_state=True, unsteady=HOIST_UP_UNSTEADY + HOIST_DOWN_UNSTEADY)
    assert _jumps(result, "up") == [(72.0, 72.1, True)]
    assert _jumps(result, "down") == [(67.9, 67.8, False)]
    from amilpy.output.sweeps import jump_lines

    assert "jump up sweeping up: between W = 72 and 72.1, HALF P-P 0.01875 -> 0.02227" in \
        jump_lines(result)[1]


def test_duffing_sweep_jumps_at_its_folds():
    """A forced Duffing oscillator (hardening, tests/references/duffing.py) swept up
    and down with its state carried: one jump down sweeping up, across the upper fold
    of its periodic orbits (1.35434, found by shooting the fold's own equations at
    rtol 1e-12), one jump up sweeping down, across the lower fold (1.20097), and
    nothing else, although the points just past each fold had not settled (their
    windows moved by 0.07) and the branches bend steeply towards the folds. The phase
    is integrated (PH), so a new W continues the forcing without a jump of its own."""
    folds = sorted(duffing.fold(w, duffing.hb_state(w, a))[0] for w, a in duffing.hb_folds())
    text = (f"PARAM W = 1.1, C = {duffing.C}, K = {duffing.K}, A = {duffing.A}, "
            f"F = {duffing.F}\nPH = INTGRL(0.0, W)\nX = INTGRL(0.0, V)\n"
            "V = INTGRL(0.0, F*COS(PH) - C*V - K*X - A*X**3)\n"
            "TIMER FINTIM = 200.0, OUTDEL = 0.05\nEND\n")
    ws = [round(1.1 + 0.02 * k, 12) for k in range(21)]
    result = amilpy.loads(text).sweep("W", ws, both_ways=True, carry_state=True,
                                      settle=150.0, measure="X")
    jumps = result.jumps()
    (up,), (down,) = jumps["up"], jumps["down"]
    assert not up.rise and up.start < folds[1] < up.stop
    assert down.rise and down.stop < folds[0] < down.start
    assert folds == pytest.approx([1.20097, 1.35434], abs=1e-5)


def test_the_first_point_of_a_carried_sweep_is_left_out():
    # the first run starts from the listing's state: its amplitude is a transient's
    values = [70.0, 70.5, 71.0, 71.5, 72.0, 72.5, 73.0, 73.5]
    amplitudes = [0.05, 0.010, 0.0101, 0.0102, 0.0103, 0.0104, 0.0105, 0.0106]
    assert _sweep(values, amplitudes, carry_state=True).jumps() == {"up": []}
    from amilpy.output.sweeps import jump_lines

    lines = jump_lines(_sweep(values, amplitudes, carry_state=True))
    assert lines[0].startswith("the first point (W = 70) starts from the listing's initial "
                               "state, a transient: it is left out of the jump search")
    assert lines[1].startswith("no jump sweeping up")
    assert jump_lines(_sweep(values[:4], amplitudes[:4]))[0].startswith(
        "sweeping up: too few points to tell a jump (it takes 6")


def test_sweep_plot_has_units_on_both_axes(tmp_path):
    from amilpy.output.sweeps import plot_sweep

    result = _sweep([1.0, 2.0, 3.0], [0.1, 0.2, 0.3])
    [path] = plot_sweep(result, str(tmp_path / "s.png"), axis_units=("rad/s", "RAD"))
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


def test_the_docs_hoist_sweep_and_response_axes_carry_units():
    # the shipped hoist's PARAM line says W is in rad/s; Y's LABEL says RAD: the
    # docs' `amilpy sweep models/hoist_backlash.amil W=...` and `response` label
    # their axes with both
    from amilpy.output import analysis
    from amilpy.output.sweeps import units

    model = amilpy.load(os.path.join(ROOT, "models", "hoist_backlash.amil"))
    result = _sweep([70.0, 71.0], [0.01, 0.02])
    result.measure = "Y"
    assert units(model, result) == ("rad/s", "RAD")
    assert analysis.units(model, "W", "Y") == ("rad/s", "RAD")


def test_a_peak_narrower_than_the_step_is_not_called_a_jump():
    # A linear oscillator (W0 = 3, ZETA = 0.05) swept in steps of 0.5: its resonance,
    # 0.3 wide, stands out of every trend like a jump, and which step was called "the
    # jump" depended on OUTDEL (hunt 49b). Swept one way, or as independent points, the
    # sweep cannot tell: it says so. Carried both ways, a jump shows its hysteresis
    # (the branch back differs) and is called one; the same values both ways are not.
    from amilpy.output.sweeps import jump_lines

    w = np.arange(1.0, 5.01, 0.25)
    a = 2.0 / np.abs(9.0 - w ** 2 + 0.3j * w)
    lines = [line for line in jump_lines(_sweep(list(w), list(a))) if "between" in line]
    assert lines and all(line.startswith("steep step") and "narrower than the step" in line
                         for line in lines)
    both = _sweep([*w, *w[::-1]], [*a, *a[::-1]], ["up"] * len(w) + ["down"] * len(w),
                  carry_state=True)
    assert all("narrower than the step" in line for line in jump_lines(both)
               if "between" in line)
    # a Duffing-like characteristic: up along the high branch to 72, down at 72.5; back
    # down along the low branch to 70.5, up at 70
    up_w = np.arange(68.0, 75.01, 0.5)
    high = np.where(up_w <= 72.0, 0.02 + 0.002 * (up_w - 68.0), 0.005 - 0.0005 * (up_w - 72.5))
    low = np.where(up_w >= 70.5, 0.005 - 0.0005 * (up_w - 72.5), 0.02 + 0.002 * (up_w - 68.0))
    hyst = _sweep([*up_w, *up_w[::-1]], [*high, *low[::-1]],
                  ["up"] * len(up_w) + ["down"] * len(up_w), carry_state=True)
    called = [line for line in jump_lines(hyst) if "between" in line]
    assert called and all(line.startswith("jump ") for line in called)
