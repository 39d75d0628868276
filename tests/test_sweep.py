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
    # The reference samples Y every 1 ms from the start of each window, like the
    # listing's OUTDEL grid, so both see the same sampled peaks; both integrate at
    # rtol 1e-9, far below the 1e-4 compared.
    ref, _ = hoist.sweep(H, ws + ws[-2::-1], 7.0, 3.0, y0=np.array(
        [EQ["X10"], EQ["Y0"], 0, 0, 0, 0]), rtol=1e-9)
    assert np.allclose(a, ref, rtol=1e-4)


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
