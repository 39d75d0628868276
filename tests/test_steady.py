"""`amilpy steady` / Model.steady: the equilibrium in the branches that hold
there, its eigenvalues and stability, and the linear model A, B, C, D, each
against a closed form written here."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from references import hoist

import amilpy
from amilpy.analysis.steady import FREE, HELD, SOLVED, NoEquilibrium
from amilpy.cli import main

MODELS = Path(__file__).resolve().parents[1] / "models"
EXAMPLES = MODELS / "examples"

# three masses in a row, springs K1 (wall-m1), K2 (m1-m2), K3 (m2-m3), dashpots C,
# a constant load F on the last mass; W integrates the power F*V3 (nothing reads it)
CHAIN = """TITLE SPRING-MASS CHAIN UNDER A CONSTANT LOAD
PARAM M1 = 1.0, M2 = 2.0, M3 = 0.5, K1 = 100.0, K2 = 300.0, K3 = 50.0, C = 0.4, F = 7.0
X1 = INTGRL(0.0, V1)
X2 = INTGRL(0.0, V2)
X3 = INTGRL(0.0, V3)
S1 = K1*X1 + C*V1
S2 = K2*(X2 - X1) + C*(V2 - V1)
S3 = K3*(X3 - X2) + C*(V3 - V2)
V1 = INTGRL(0.0, (S2 - S1)/M1)
V2 = INTGRL(0.0, (S3 - S2)/M2)
V3 = INTGRL(0.0, (F - S3)/M3)
W  = INTGRL(0.0, F*V3)
TIMER FINTIM = 1.0, OUTDEL = 0.01
OUTPUT X3
END
"""


def chain_a() -> tuple[list[str], np.ndarray]:
    """The chain's A matrix in the order amilpy sorts the states (V1 V2 V3 X1 X2
    X3), written from the equations above."""
    m1, m2, m3, k1, k2, k3, c = 1.0, 2.0, 0.5, 100.0, 300.0, 50.0, 0.4
    # d/dt [V1 V2 V3 X1 X2 X3]
    a = np.zeros((6, 6))
    a[0, :] = [-2 * c / m1, c / m1, 0, -(k1 + k2) / m1, k2 / m1, 0]
    a[1, :] = [c / m2, -2 * c / m2, c / m2, k2 / m2, -(k2 + k3) / m2, k3 / m2]
    a[2, :] = [0, c / m3, -c / m3, 0, k3 / m3, -k3 / m3]
    a[3, 0] = a[4, 1] = a[5, 2] = 1.0
    return ["V1", "V2", "V3", "X1", "X2", "X3"], a


@pytest.fixture
def chain(tmp_path):
    path = tmp_path / "chain.amil"
    path.write_text(CHAIN)
    return path


def test_a_chain_under_load_settles_where_each_spring_carries_the_load(chain):
    # Closed form: every spring carries F, so X1 = F/K1, X2 = X1 + F/K2, X3 = X2 + F/K3;
    # the equations are linear, so Newton lands on it in one step: to 1e-12.
    # W (the work done) is read by nothing: free, its rate F*V3 = 0 there.
    eq = amilpy.load(chain).steady()
    x1 = 7.0 / 100.0
    x2 = x1 + 7.0 / 300.0
    x3 = x2 + 7.0 / 50.0
    assert [eq["X1"], eq["X2"], eq["X3"]] == pytest.approx([x1, x2, x3], rel=1e-12)
    assert [eq["V1"], eq["V2"], eq["V3"]] == pytest.approx([0, 0, 0], abs=1e-14)
    assert eq.roles["W"] == FREE and eq.roles["X1"] == SOLVED
    assert eq.how == "Newton" and eq.residual <= 1e-10
    assert eq.stability == "stable" and eq.zero_modes == 0


def test_the_chain_linear_model_is_its_equations(chain):
    # A from the model's Jacobian against the matrix written by hand (exact to
    # rounding: 1e-12); B = dF/dF = 1/M3 on V3 only; C of the spring force S3 =
    # K3 (X3 - X2) + C (V3 - V2) is its coefficients; D = 0 (differences of linear
    # functions: 1e-9).
    eq = amilpy.load(chain).steady(inputs=["F"], outputs=["X3", "S3"])
    names, a = chain_a()
    lin = eq.linear
    assert lin.states == names
    assert lin.a == pytest.approx(a, rel=1e-12, abs=1e-12)
    assert lin.b[:, 0] == pytest.approx([0, 0, 1 / 0.5, 0, 0, 0], abs=1e-9)
    assert lin.c[0] == pytest.approx([0, 0, 0, 0, 0, 1], abs=1e-12)
    assert lin.c[1] == pytest.approx([0, -0.4, 0.4, 0, -50.0, 50.0], rel=1e-9, abs=1e-9)
    assert lin.d == pytest.approx(np.zeros((2, 1)), abs=1e-9)
    # the static gain of the transfer function is the compliance 1/K1 + 1/K2 + 1/K3
    g0 = lin.transfer(np.array([1e-6]))[0, 0, 0]
    assert g0.real == pytest.approx(1 / 100 + 1 / 300 + 1 / 50, rel=1e-6)
    # the eigenvalues are A's
    assert sorted(m.wn for m in eq.modes) == pytest.approx(
        sorted({abs(v) for v in np.linalg.eigvals(a) if v.imag >= 0}), rel=1e-10)


def test_the_hoist_finds_its_loaded_equilibrium_from_rest():
    # From the listing's rest state (teeth mid-gap: that branch cannot carry the
    # load, Newton cannot solve it) the pseudo-transient steps close the gap; the
    # answer is the docs' hand-typed X10 = MN/C1, Y0 = DELTA/2 + MN/C2 (1e-12 of the
    # closed form; the docs' rounded values to their 6 digits), teeth in contact
    # (a branch), the drift V1 = V2 = V3 kept at the listing's 0, the phase PH held
    # (its rate W reads no state), the eigenfrequencies eq. 16's.
    eq = amilpy.load(MODELS / "hoist_backlash.amil").steady()
    h = hoist.Hoist()
    assert eq["X1"] == pytest.approx(h.mn / h.c1, rel=1e-12)
    assert eq["Y"] == pytest.approx(hoist.DELTA / 2 + h.mn / h.c2, rel=1e-12)
    assert eq["X1"] == pytest.approx(1.91892e-3, rel=5e-6)
    assert eq["Y"] == pytest.approx(0.024350, rel=5e-6)
    # (0 to rounding: the linear algebra's rounding differs between machines, 0 on one,
    # 2e-20 on another; velocities here are of order W = 70 rad/s)
    assert [eq["V1"], eq["V2"], eq["V3"]] == pytest.approx([0, 0, 0], abs=1e-15)
    assert eq.roles["PH"] == HELD and eq.rates[eq.names.index("PH")] == 70.0
    assert dict(eq.surfaces)["ABS(Y) - DH"] == 1.0
    assert "pseudo-transient" in eq.how
    assert eq.stability == "stable" and eq.zero_modes == 1  # the drift
    lam2, lam3 = hoist.linear_frequencies(h, h.c2)
    assert sorted(m.wn for m in eq.modes if not m.zero) == pytest.approx([lam2, lam3],
                                                                         rel=1e-12)


DEAD_ZONE = """TITLE MASS ON A SPRING WITH A GAP
PARAM K = 200.0, C = 3.0, M = 1.5, F = 4.0, D = 0.01
X = INTGRL(0.0, V)
V = INTGRL(0.0, (F - K*DEADSP(-D, D, X) - C*V)/M)
TIMER FINTIM = 1.0, OUTDEL = 0.01
OUTPUT X
END
"""


@pytest.mark.parametrize("load, edge", [(4.0, 1), (-4.0, -1)])
def test_the_dead_zone_branch_is_part_of_the_answer(tmp_path, load, edge):
    # X = edge*D + F/K: the spring is engaged on the side the load pushes to.
    path = tmp_path / "gap.amil"
    path.write_text(DEAD_ZONE)
    eq = amilpy.load(path).steady(F=load)
    assert eq["X"] == pytest.approx(edge * 0.01 + load / 200.0, rel=1e-12)
    assert eq["V"] == pytest.approx(0.0, abs=1e-15)
    assert eq.stability == "stable"


PENDULUM = """TITLE PENDULUM
PARAM G = 9.81, L = 0.5, B = 0.2
TH = INTGRL(0.5, OM)
OM = INTGRL(0.0, -G/L*SIN(TH) - B*OM)
TIMER FINTIM = 1.0, OUTDEL = 0.01
OUTPUT TH
END
"""


def test_the_pendulum_hangs_stably_and_stands_unstably(tmp_path):
    # From TH = 0.5 Newton finds TH = 0 (eigenvalues of x'' + B x' + G/L x: stable);
    # from --guess TH=3 it finds TH = PI, a saddle with eigenvalues
    # (-B +- sqrt(B^2 + 4 G/L))/2 (1e-10: a Jacobian of SIN at a root).
    path = tmp_path / "pendulum.amil"
    path.write_text(PENDULUM)
    model = amilpy.load(path)
    down = model.steady()
    assert down["TH"] == pytest.approx(0.0, abs=1e-14) and down.stability == "stable"
    up = model.steady(guess={"TH": 3.0})
    assert up["TH"] == pytest.approx(math.pi, rel=1e-14)
    assert up.stability == "unstable"
    root = math.sqrt(0.2 ** 2 + 4 * 9.81 / 0.5)
    assert sorted(m.eigenvalue.real for m in up.modes) == pytest.approx(
        [(-0.2 - root) / 2, (-0.2 + root) / 2], rel=1e-10)


def test_no_equilibrium_is_an_error_that_says_why(tmp_path, capsys):
    # X' = 1 + X^2 is never zero: exit 3, the residual and what to try.
    path = tmp_path / "none.amil"
    path.write_text("X = INTGRL(0.0, 1.0 + X*X)\nTIMER FINTIM = 1.0\nOUTPUT X\nEND\n")
    with pytest.raises(NoEquilibrium, match="no equilibrium found"):
        amilpy.load(path).steady()
    assert main(["steady", str(path)]) == 3
    err = capsys.readouterr().err
    assert "no equilibrium found" in err and "dX/dt" in err and "--guess" in err


def test_steady_writes_csv_matrices_npz_and_bode(chain, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    eq_csv, m_csv, npz = out / "eq.csv", out / "abcd.csv", out / "lin.npz"
    code = main(["steady", str(chain), "--input", "F", "--output", "X3", "--csv",
                 str(eq_csv), "--matrices", str(m_csv), "--npz", str(npz), "--bode",
                 "--out", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert text.startswith("EQUILIBRIUM OF SPRING-MASS CHAIN UNDER A CONSTANT LOAD")
    assert "STABLE: every mode decays" in text and "LINEAR MODEL" in text
    with open(eq_csv, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["NAME", "VALUE", "RATE", "ROLE"]
    assert {r[0]: r[3] for r in rows[1:]}["W"] == "free"
    assert float({r[0]: r[1] for r in rows[1:]}["X1"]) == pytest.approx(0.07, rel=1e-12)
    with open(m_csv, newline="") as fh:
        long = list(csv.reader(fh))
    assert long[0] == ["MATRIX", "ROW", "COLUMN", "VALUE"]
    assert ["B", "V3", "F"] in [r[:3] for r in long]
    data = np.load(npz)
    names, a = chain_a()
    assert list(data["states"]) == names and data["A"] == pytest.approx(a, abs=1e-12)
    assert data["B"].shape == (6, 1) and data["C"].shape == (1, 6)
    png = out / "chain_bode_F.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_steady_usage_errors(chain, capsys):
    assert main(["steady", str(chain), "--bode"]) == 2
    assert "--input" in capsys.readouterr().err
    assert main(["steady", str(chain), "--linear", "--input", "F"]) == 2
    assert "--output NAME" in capsys.readouterr().err
    assert main(["steady", str(chain), "--guess", "Q=1"]) == 2
    assert "not a state" in capsys.readouterr().err
    assert main(["steady", str(chain), "--guess", "X1=abc"]) == 2
    assert "--guess X1" in capsys.readouterr().err
    assert main(["steady", str(chain), "--input", "NOPE", "--output", "X3"]) == 2
    assert "not a PARAM" in capsys.readouterr().err


def test_a_listing_with_nothing_to_solve_for_says_so(tmp_path, capsys):
    # X' = C: X is free (nothing reads it); there is no state to bring to rest, and
    # the printout says so instead of calling it stable; X cannot be an output of a
    # linear model whose states it is not among.
    path = tmp_path / "clock.amil"
    path.write_text("PARAM C = 1.0\nX = INTGRL(0.0, C)\nTIMER FINTIM = 1.0\nPRINT X\nEND\n")
    eq = amilpy.load(path).steady()
    assert eq.stability == "none" and eq.roles["X"] == FREE
    assert main(["steady", str(path)]) == 0
    out = capsys.readouterr().out
    assert "NO STATE TO SOLVE FOR" in out and "X keeps changing" in out
    assert main(["steady", str(path), "--input", "C", "--output", "X"]) == 2
    assert "no state of the linear model" in capsys.readouterr().err


def test_a_start_the_field_cannot_be_had_at_is_a_clear_failure(tmp_path, capsys):
    # A NaN initial value, and a field that faults wherever the search looks: exit 3
    # with what to give, never a traceback.
    nan = tmp_path / "nan.amil"
    nan.write_text("PARAM K = 0.5\nINITIAL\n   R = SQRT(K - 1.0)\nDYNAMIC\n"
                   "X = INTGRL(R, -X)\nTIMER FINTIM = 1.0\nPRINT X\nEND\n")
    assert main(["steady", str(nan)]) == 3
    assert "the start is not finite (X = nan)" in capsys.readouterr().err
    # (IMPL's loop has no value at the guess: the search goes where it has one, and
    # says what it found -- since the Jacobian of a field with a loop is differenced,
    # 2026-12-01, it gets there instead of stopping at the guess)
    assert main(["steady", str(EXAMPLES / "csmp_diode_filter.amil")]) == 3
    assert "no equilibrium found" in capsys.readouterr().err


def test_a_small_input_is_moved_by_a_fraction_of_itself(tmp_path):
    # X' = 1E-10/A - X with A = 1E-10: X = 1E-10/A = 1 at rest, B = d(X')/dA =
    # -1E-10/A^2 = -1E10 (a step of 1e-8 would be a hundred times A itself).
    path = tmp_path / "small.amil"
    path.write_text("PARAM A = 1.0E-10\nX = INTGRL(0.0, 1.0E-10/A - X)\nTIMER FINTIM = 1.0\n"
                    "PRINT X\nEND\n")
    eq = amilpy.load(path).steady(inputs="A", outputs="X")
    assert eq["X"] == pytest.approx(1.0, rel=1e-12)
    assert eq.linear.b[0, 0] == pytest.approx(-1e10, rel=1e-8)
