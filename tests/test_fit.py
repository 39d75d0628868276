"""`amilpy fit` / `Model.fit`: data values fitted to observations by weighted least
squares. Noise-free observations made from closed forms (not from the model
itself) must give back the values they were made with; noisy ones, intervals
that hold the truth at their stated rate."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT

import amilpy
from amilpy.cli import main
from amilpy.diagnostics import AmilError, UsageError

# x' = -K x, x(0) = X0: x = X0 exp(-K t)
DECAY = """TITLE DECAY
INCON X0 = 2.0
PARAM K = 1.5   ! [1/s] rate
X = INTGRL(X0, -K*X)
TIMER FINTIM = 2.0, OUTDEL = 0.1
OUTPUT X
END
"""

# a block sliding on dry friction from 2 m/s: it stops at t* = 2/(MU G) and stays;
# x = 2 t - MU G t^2 / 2 until then, 2 / MU G after. MU moves the switching instant.
FRICTION = """TITLE SLIDING BLOCK
PARAM MU = 0.3
CONST G = 9.81
A = FSW(V, MU*G, 0.0, -MU*G)
V = INTGRL(2.0, A)
X = INTGRL(0.0, V)
TIMER FINTIM = 1.5, OUTDEL = 0.1
OUTPUT X
END
"""


def _csv(tmp_path, header: str, rows, name: str = "obs.csv") -> str:
    path = tmp_path / name
    path.write_text(header + "\n" + "".join(",".join(repr(float(v)) for v in r) + "\n"
                                            for r in rows))
    return str(path)


def test_noise_free_data_give_back_the_values_of_a_smooth_model(tmp_path):
    """X0 = 1.7, K = 0.8 from exp: recovered to 1e-6 relative (the runs are good to
    ~1e-9; the fit stops at 1e-10 of a step), starting from the listing's 2.0, 1.5."""
    t = np.linspace(0.1, 2.0, 12)
    data = _csv(tmp_path, "TIME,X", zip(t, 1.7 * np.exp(-0.8 * t), strict=True))
    fit = amilpy.loads(DECAY).fit(data, ["X0", "K=0:10"], weights="none")
    assert fit.success and fit.names == ["X0", "K"]
    assert fit.estimates == pytest.approx([1.7, 0.8], rel=1e-6)
    assert fit.start == [2.0, 1.5]


def test_a_value_that_moves_a_switching_instant_is_recovered(tmp_path):
    """MU = 0.2 from the closed form of a block stopping on dry friction (stop at
    1.019 s, inside the data): the observations after the stop depend on MU only
    through that instant, located by the runs, so the fit finds it to 1e-6."""
    mu, g = 0.2, 9.81
    stop = 2.0 / (mu * g)
    t = np.arange(0.125, 1.5, 0.125)
    x = np.where(t < stop, 2.0 * t - 0.5 * mu * g * t * t, 2.0 * stop - 0.5 * mu * g * stop ** 2)
    data = _csv(tmp_path, "TIME,X", zip(t, x, strict=True))
    fit = amilpy.loads(FRICTION).fit(data, ["MU=0.05:1"], weights="none")
    assert fit.success
    assert fit.estimates[0] == pytest.approx(mu, rel=1e-6)


@pytest.mark.parametrize("gradients", ["differences", "sensitivities"])
def test_a_dosing_program_fitted_on_a_log_scale(tmp_path, gradients):
    """The shipped oral-dosing ACSL program (DISCRETE doses every 12 h): KA and KE
    from plasma concentrations made by superposing one Bateman curve per dose, KA
    = 0.9 and KE = 0.21 /h, fitted on a log scale from the listing's 1.2 and 0.173;
    by differences of runs, and by the program's tangent through its doses."""
    ka, ke, dose, vd = 0.9, 0.21, 500.0, 42.0
    t = np.array([1.0, 2.0, 4.0, 8.0, 11.5, 13.0, 18.0, 25.0, 36.5, 49.0, 60.0, 70.0])
    cp = sum(np.where(t >= d, dose * ka / (vd * (ka - ke)) *
                      (np.exp(-ke * (t - d)) - np.exp(-ka * (t - d))), 0.0)
             for d in (0.0, 12.0, 24.0, 36.0, 48.0, 60.0))
    data = _csv(tmp_path, "T,CP", zip(t, cp, strict=True))
    model = amilpy.load(f"{ROOT}/models/examples/oral_dosing.csl")
    fit = model.fit(data, ["KA=0.01:10", "KE=0.01:10"], log=["KA", "KE"], weights="relative",
                    gradients=gradients)
    assert fit.success
    assert fit.estimates == pytest.approx([ka, ke], rel=1e-6)
    assert abs(fit.correlation[0, 1]) < 1.0
    if gradients == "sensitivities":
        assert fit.gradients == "variational equations (sensitivities through the " \
            "switches and the program's DISCRETE and DYNAMIC code)" and fit.jacobians >= 1


@pytest.mark.slow  # (100 seeded fits: 6 s; CI runs it in its slow step)
def test_the_95_percent_intervals_hold_the_truth_at_their_rate(tmp_path):
    """Coverage: 100 seeded data sets of the decay with normal noise of SD 0.02 (given
    as SD_X); the 95 % interval of K must hold K = 0.8 in about 95 of them. A
    binomial(100, 0.95) falls below 88 with probability 0.001, so 88..100 is the
    band (seeded: the count is the same at every run of the test)."""
    t = np.linspace(0.1, 2.0, 10)
    model = amilpy.loads(DECAY.replace("INCON X0 = 2.0", "INCON X0 = 1.7"))
    rng = np.random.default_rng(2026)
    held = 0
    for _ in range(100):
        y = 1.7 * np.exp(-0.8 * t) + rng.normal(0.0, 0.02, t.size)
        data = _csv(tmp_path, "TIME,X,SD_X", zip(t, y, np.full(t.size, 0.02), strict=True))
        fit = model.fit(data, ["K=0.1:5"], weights="sd")
        held += fit.lower[0] <= 0.8 <= fit.upper[0]
    assert 88 <= held <= 100, held


def test_the_command_prints_the_estimates_and_writes_the_listing(tmp_path, capsys):
    """`amilpy fit`: the estimates table, the CSV, and --write: the listing with the
    fitted value in place, its comment kept, which runs to the same numbers."""
    listing = tmp_path / "decay.amil"
    listing.write_text(DECAY)
    t = np.linspace(0.1, 2.0, 12)
    data = _csv(tmp_path, "TIME,X", zip(t, 2.0 * np.exp(-0.8 * t), strict=True))
    out_csv, written = tmp_path / "est.csv", tmp_path / "fitted.amil"
    code = main(["fit", str(listing), "--data", data, "--free", "K=0:10", "--csv",
                 str(out_csv), "--write", str(written)])
    out = capsys.readouterr().out
    assert code == 0
    assert "FIT  (none weights, 12 observations, 1 value(s)" in out
    row = next(line for line in out.splitlines() if line.startswith("K "))
    assert float(row.split()[2]) == pytest.approx(0.8, rel=1e-6)
    lines = out_csv.read_text().splitlines()
    assert lines[0] == "NAME,START,ESTIMATE,SE,LOWER95,UPPER95"
    assert float(lines[1].split(",")[2]) == pytest.approx(0.8, rel=1e-6)
    text = written.read_text()
    (line,) = [x for x in text.splitlines() if x.startswith("PARAM K = ")]
    assert float(line.split()[3]) == pytest.approx(0.8, rel=1e-6) and "! [1/s] rate" in line
    run = amilpy.load(str(written)).run()[0]
    assert run["X"][-1] == pytest.approx(2.0 * math.exp(-1.6), rel=1e-6)


@pytest.mark.parametrize("free, kw, words", [
    (["Q"], {}, "Q is not a PARAM/CONST/INCON value"),
    (["K=2:1"], {}, "lower bound must be below"),
    (["K=2:3"], {}, "K = 1.5 is outside its bounds"),
    (["K"], {"log": ["X0"]}, "X0 is not one of the values fitted"),
    (["K"], {"weights": "sd"}, "needs an SD_<NAME> column"),
])
def test_a_fit_that_cannot_be_asked_is_a_usage_error(tmp_path, free, kw, words):
    data = _csv(tmp_path, "TIME,X", [(0.5, 1.0), (1.0, 0.6)])
    with pytest.raises(UsageError, match=words.replace("(", r"\(")):
        amilpy.loads(DECAY).fit(data, free, **kw)


def test_the_docs_dosing_example_prints_what_the_docs_say():
    """docs/fitting.md shows the KA/KE fit of the shipped dosing program; its
    estimates and standard errors are what the command gives (7 digits)."""
    doc = (Path(ROOT) / "docs" / "fitting.md").read_text()
    shown = {line.split()[0]: [float(x) for x in line.split()[1:]]
             for line in doc.splitlines()
             if line.startswith(("KA  ", "KE  ")) and len(line.split()) == 6}
    model = amilpy.load(f"{ROOT}/models/examples/oral_dosing.csl")
    fit = model.fit(f"{ROOT}/models/examples/data/oral_dosing_cp.csv",
                    ["KA=0.01:10", "KE=0.01:10"], log=["KA", "KE"], weights="relative")
    for k, name in enumerate(fit.names):
        start, estimate, se, lower, upper = shown[name]
        assert [estimate, se, lower, upper] == pytest.approx(
            [fit.estimates[k], fit.se[k], fit.lower[k], fit.upper[k]], rel=1e-6)


def test_known_sds_give_normal_intervals_and_none_left_gives_no_errors(tmp_path):
    """With the data's own SDs the residual variance is known: the interval is the
    estimate +- 1.96 SE (the normal quantile, not Student's t, which made it 2.2
    times too wide with two degrees of freedom). With the variance estimated and as
    many values as observations nothing is left to estimate it: no SE, said."""
    t = np.array([0.5])
    sd = _csv(tmp_path, "TIME,X,SD_X", [(0.5, 1.7 * math.exp(-0.4), 0.05)], "sd.csv")
    fit = amilpy.loads(DECAY.replace("INCON X0 = 2.0", "INCON X0 = 1.7")).fit(
        sd, ["K=0.1:5"], weights="sd")
    assert fit.estimates[0] == pytest.approx(0.8, rel=1e-6)
    assert fit.upper[0] - fit.estimates[0] == pytest.approx(1.959964 * fit.se[0], rel=1e-6)
    none = _csv(tmp_path, "TIME,X", zip(t, 1.7 * np.exp(-0.8 * t), strict=True))
    fit = amilpy.loads(DECAY.replace("INCON X0 = 2.0", "INCON X0 = 1.7")).fit(
        none, ["K=0.1:5"], weights="none")
    assert math.isnan(fit.se[0]) and math.isnan(fit.lower[0])
    assert any("no degrees of freedom" in n for n in fit.notes)


def test_a_value_stopped_at_its_bound_is_said(tmp_path):
    t = np.linspace(0.1, 2.0, 8)
    data = _csv(tmp_path, "TIME,X", zip(t, 2.0 * np.exp(-0.8 * t), strict=True))
    fit = amilpy.loads(DECAY).fit(data, ["K=1.0:3"], weights="none")
    assert fit.estimates[0] == pytest.approx(1.0)
    assert any("K stopped at its lower bound 1" in n for n in fit.notes), fit.notes


def test_values_the_data_cannot_determine_are_said(tmp_path):
    """X' = -K1 K2 X: only the product is in the data, so the fit's Jacobian has a
    zero singular value (d X/d K1 = (K2/K1) d X/d K2): "the data cannot determine".
    And a value that moves X by about the noise (B, with X' = -K X + 5E-3
    B) gets a 95 % interval wider than its bounds -1:1, said in words."""
    t = np.linspace(0.1, 2.0, 12)
    data = _csv(tmp_path, "TIME,X", zip(t, 2.0 * np.exp(-0.8 * t), strict=True))
    product = amilpy.loads(DECAY.replace("PARAM K = 1.5   ! [1/s] rate",
                                         "PARAM K1 = 1.0, K2 = 1.5")
                           .replace("-K*X", "-K1*K2*X"))
    fit = product.fit(data, ["K1=0.1:10", "K2=0.1:10"], weights="none")
    assert any(n.startswith("the data cannot determine K") for n in fit.notes), fit.notes
    noise = np.random.default_rng(1).normal(0.0, 0.01, t.size)  # (B lands inside, 0.76)
    noisy = _csv(tmp_path, "TIME,X", zip(t, 2.0 * np.exp(-0.8 * t) + noise, strict=True),
                 "noisy.csv")
    weak = amilpy.loads(DECAY.replace("PARAM K = 1.5   ! [1/s] rate",
                                      "PARAM K = 1.5, B = 0.5").replace("-K*X", "-K*X + 5.0E-3*B"))
    fit = weak.fit(noisy, ["K=0.1:5", "B=-1:1"], weights="none")
    assert any(n.startswith("B: the 95 % interval") and "wider than its bounds -1:1" in n
               for n in fit.notes), fit.notes


def test_a_fit_refuses_what_it_cannot_compare(tmp_path):
    """A run that a FINISH stops before some observations (the residuals would change
    length from one evaluation to the next: a SciPy traceback) and relative weights
    of an observation of 0 (a residual of 1e297): each an error saying what to do,
    the second at the observation's line and column."""
    fall = ("PARAM G = 15.0\nV = INTGRL(0.0, -G)\nX = INTGRL(10.0, V)\nFINISH X = 0.0\n"
            "TIMER FINTIM = 2.0, OUTDEL = 0.01\nOUTPUT X\nEND\n")
    t = np.arange(0.1, 1.45, 0.1)
    data = _csv(tmp_path, "TIME,X", zip(t, 10.0 - 0.5 * 9.81 * t * t, strict=True))
    with pytest.raises(AmilError, match="stops at TIME = 1.1547.*before 3 observation"):
        amilpy.loads(fall).fit(data, ["G=1:20"], weights="none")
    zero = _csv(tmp_path, "TIME,X", [(0.5, 1.0), (1.0, 0.0)], "zero.csv")
    with pytest.raises(AmilError, match="divides by") as err:
        amilpy.loads(DECAY).fit(zero, ["K"], weights="relative")
    assert (err.value.line, err.value.column) == (3, 5)


# a ball dropped from 1 m onto a spring-dashpot floor: the floor's force -K X - C V
# acts while X < 0 and jumps at X = 0 (the dashpot's part, the ball moving): each
# contact begins and ends at a located switch, whose instant C and K move
BALL = """TITLE A BALL ON A SPRING-DASHPOT FLOOR
PARAM C = 2.0, K = 400.0
CONST G = 9.81
F = FSW(X, -K*X - C*V, 0.0, 0.0)
V = INTGRL(0.0, -G + F)
X = INTGRL(1.0, V)
TIMER FINTIM = 1.5, OUTDEL = 0.01
PRINT X, V, F
END
"""


def _ball_scipy(c: float, k: float, t: np.ndarray) -> np.ndarray:
    """The ball written again with SciPy: one solve_ivp per phase, the contact's
    start and end found by its events (rtol 1e-12): X at the instants t."""
    from scipy.integrate import solve_ivp

    def free(_, y):
        return [y[1], -9.81]

    def contact(_, y):
        return [y[1], -9.81 - k * y[0] - c * y[1]]

    def down(_, y):  # (into the floor, and out of it: events by direction)
        return y[0]

    def up(_, y):
        return y[0]

    down.terminal = up.terminal = True
    down.direction, up.direction = -1.0, 1.0
    out, y, t0, phase = np.full(len(t), np.nan), [1.0, 0.0], 0.0, free
    while t0 < t[-1]:
        sol = solve_ivp(phase, (t0, t[-1]), y, rtol=1e-12, atol=1e-14,
                        events=down if phase is free else up, dense_output=True,
                        method="DOP853")
        inside = (t >= t0) & (t <= sol.t[-1])
        out[inside] = sol.sol(t[inside])[0]
        if sol.status != 1:
            break
        t0, y = sol.t[-1], [0.0, sol.y[1, -1]]
        phase = contact if phase is free else free
    return out


def test_sensitivities_through_switches_agree_with_differences(tmp_path):
    """d X/d C and d X/d K and those of the force F (an output, no state) at instants
    before, inside and after the contacts, from the variational equations with the
    tangent's jump at each located switch: equal to central differences of whole
    runs at RELERR 1e-12 (steps of 1e-4 of each value) to 1e-6 of each column's
    largest (the differences' own error: (1e-4)^2 and 1e-12/1e-4)."""
    from amilpy.analysis.sensitivity import observed_jacobian
    from amilpy.observed import read

    t = np.array([0.3, 0.5, 0.55, 0.6, 0.8, 1.0, 1.2, 1.4])
    path = _csv(tmp_path, "TIME,X,F", [(x, 0.0, 0.0) for x in t])
    model = amilpy.loads(BALL)
    obs = read(path, model.ir.variables, 1)
    exact, why = observed_jacobian(model, obs, ["C", "K"], {"C": 2.0, "K": 400.0}, {}, {})
    assert why == "" and exact.shape == (16, 2)

    def simulated(**kw):
        run = model.run(advice=False, data=obs, rtol=1e-12, atol=1e-15, **kw)[0]
        return np.concatenate([c.simulated for c in run.observed])

    cols = [(simulated(**{n: v * (1 + 1e-4)}) - simulated(**{n: v * (1 - 1e-4)}))
            / (2e-4 * v) for n, v in (("C", 2.0), ("K", 400.0))]
    diff = np.column_stack(cols)
    assert np.max(np.abs(exact - diff) / np.max(np.abs(diff), axis=0)) < 1e-6


def test_a_programs_sensitivities_agree_with_differences(tmp_path):
    """The dosing program's d CP/d (KA, KE, DOSE) and d AG/d (...) at observed CINT
    rows, at a dosing instant (12: after its dose) and at the last (72, where a
    dose is given before the TERMT ends the run): the tangent through the
    DISCRETE code equal to central differences of whole runs at RELERR 1e-12 (steps
    of 1e-4 of each value) to 1e-6 of each column's largest."""
    from amilpy.analysis.sensitivity import observed_jacobian
    from amilpy.observed import read

    t = np.array([0.5, 5.5, 12.0, 12.5, 30.5, 47.5, 72.0])
    path = _csv(tmp_path, "T,CP,AG", [(x, 0.0, 0.0) for x in t])
    model = amilpy.load(f"{ROOT}/models/examples/oral_dosing.csl")
    obs = read(path, model.ir.variables, 1)
    p = {"KA": 1.2, "KE": 0.173, "DOSE": 500.0}
    exact, why = observed_jacobian(model, obs, list(p), p, {}, {})
    assert why == "" and exact.shape == (14, 3)

    def simulated(**kw):
        run = model.run(advice=False, data=obs, rtol=1e-12, atol=1e-15, **kw)[0]
        return np.concatenate([c.simulated for c in run.observed])

    diff = np.column_stack([(simulated(**{n: v * (1 + 1e-4)}) -
                             simulated(**{n: v * (1 - 1e-4)})) / (2e-4 * v)
                            for n, v in p.items()])
    assert np.max(np.abs(exact - diff) / np.max(np.abs(diff), axis=0)) < 1e-6


def test_a_fit_with_sensitivities_recovers_the_ball_written_again_with_scipy(tmp_path):
    """C = 3 and K = 300 from X at 12 instants made by the SciPy version of the ball:
    recovered to 1e-6 with the variational equations' Jacobian, and said so."""
    t = np.linspace(0.1, 1.45, 12)
    data = _csv(tmp_path, "TIME,X", zip(t, _ball_scipy(3.0, 300.0, t), strict=True))
    fit = amilpy.loads(BALL).fit(data, ["C=0.1:20", "K=50:2000"], weights="none",
                                 gradients="sensitivities")
    assert fit.estimates == pytest.approx([3.0, 300.0], rel=1e-6)
    assert fit.gradients.startswith("variational equations") and fit.jacobians >= 1


STICK = """TITLE BLOCK STOPPED BY DRY FRICTION, THEN PUSHED OFF AGAIN
PARAM MU = 0.3, AR = 1.0
CONST G = 9.81
A = AR*TIME + FSW(V, MU*G, 0.0, -MU*G)
V = INTGRL(2.0, A)
X = INTGRL(0.0, V)
TIMER FINTIM = 4.0, OUTDEL = 0.1
OUTPUT X
END
"""


def _stick(t: float, mu, ar, g: float = 9.81):
    """The block's X: it slows (V = 2 + AR t^2/2 - MU G t) until V = 0 at t1, sticks
    while the push AR t is below MU G, and slides off at t2 = MU G/AR."""
    t1 = (mu * g - np.sqrt(mu * mu * g * g - 4 * ar)) / ar
    t2 = mu * g / ar
    x1 = 2 * t1 + ar * t1 ** 3 / 6 - mu * g * t1 ** 2 / 2
    if t < np.real(t1):
        return 2 * t + ar * t ** 3 / 6 - mu * g * t ** 2 / 2
    if t < np.real(t2):
        return x1
    return x1 + ar / 2 * ((t ** 3 - t2 ** 3) / 3 - t2 ** 2 * (t - t2)) - mu * g * (t - t2) ** 2 / 2


def test_sensitivities_through_sticking_are_the_closed_forms():
    """Dry friction holds the block from t1 = 0.784 s to t2 = 2.943 s (Filippov's
    sliding on V = 0, both ends moved by MU and AR): d X/d MU and d X/d AR in each
    phase equal the complex-step derivative of the closed form to 1e-8 relative;
    d A/d MU is 0 while it sticks (A = 0 whatever MU) and -G before. The tangent
    jumps onto the surface where it sticks and is continuous where it slides off;
    before sliding was followed the fit differenced whole runs here."""
    from amilpy.analysis.sensitivity import trajectory

    times = [0.5, 1.5, 2.5, 3.0, 3.5, 4.0]
    track = trajectory(amilpy.loads(STICK), 0, ["MU", "AR"], {"MU": 0.3, "AR": 1.0}, {},
                       times)
    assert not isinstance(track, str), track
    for t in times:
        exact = [_stick(t, 0.3 + 1e-30j, 1.0).imag / 1e-30,
                 _stick(t, 0.3, 1.0 + 1e-30j).imag / 1e-30]
        assert track.row("X", t) == pytest.approx(exact, rel=1e-8), t
    assert track.row("A", 1.5) == pytest.approx([0.0, 0.0], abs=1e-9)
    assert track.row("A", 0.5) == pytest.approx([-9.81, 0.5], rel=1e-9)
    # the flow map's too (the monodromy of `periodic`): from (V0, X0) = (2, 0) to
    # TIME 4, d V/d V0 = 0 (it slides off at t2 = MU G/AR, whatever V0) and d X/d V0 =
    # t1 (X(t1) = V0 t1 + AR t1^3/6 - MU G t1^2/2 with V(t1) = 0)
    flow = amilpy.loads(STICK).flow()
    _, _, phi = flow.advance(flow.initial_state(), 0.0, 4.0, sensitivity=True)
    assert flow.last_sensitivity == "variational equations"
    v, x = flow.state_names.index("V"), flow.state_names.index("X")
    t1 = (0.3 * 9.81 - np.sqrt((0.3 * 9.81) ** 2 - 4.0)) / 1.0
    assert [phi[v, v], phi[x, v], phi[x, x]] == pytest.approx([0.0, t1, 1.0], abs=1e-8)


def test_sensitivities_where_a_push_ends_the_slide_and_on_a_moving_surface():
    """A block stuck by dry friction (from 0.68 s) is pushed off at T1 by P STEP(T1)
    (P > MU G): V = (P - MU G)(t - T1) after, so d X/d T1 = -(P - MU G)(t - T1) and
    d X/d P = (t - T1)^2/2 -- the push's switch at T1 ends the slide at once (its
    weight jumps past 1), and its jump is to the branch the block leaves on (it was
    0, on the sliding field, until review 48). A block on a belt that accelerates
    (surface V - AB TIME, no constant gradient) sticks at t1 (Newton on the free
    motion) and is carried: F = A + K X = AB + K X; d F/d MU and d F/d AB against
    the complex-step derivative of that closed form, to 1e-6 (the surface's slopes
    by differences: about 1e-3 with the run's look-ahead, before review 48)."""
    from amilpy.analysis.sensitivity import trajectory

    push = STICK.replace("PARAM MU = 0.3, AR = 1.0", "PARAM MU = 0.3, P = 4.0, T1 = 1.5") \
        .replace("A = AR*TIME + FSW(V, MU*G, 0.0, -MU*G)",
                 "A = FSW(V, MU*G, 0.0, -MU*G) + P*STEP(T1)").replace("4.0, OUTDEL", "3.0, OUTDEL")
    track = trajectory(amilpy.loads(push), 0, ["T1", "P"], {"MU": 0.3, "P": 4.0, "T1": 1.5},
                       {}, [1.4, 2.0, 3.0])
    for t in (1.4, 2.0, 3.0):
        s = max(t - 1.5, 0.0)
        assert track.row("X", t) == pytest.approx([-(4.0 - 0.3 * 9.81) * s, s * s / 2],
                                                  abs=1e-8), t
    belt = """TITLE BLOCK ON AN ACCELERATING BELT
PARAM MU = 0.4, AB = 1.0, K = 4.0
CONST G = 9.81
A = -K*X + FSW(V - AB*TIME, MU*G, 0.0, -MU*G)
V = INTGRL(0.5, A)
X = INTGRL(0.0, V)
F = A + K*X
TIMER FINTIM = 1.0, OUTDEL = 0.05
OUTPUT X, F
END
"""

    def carried(mu, ab, t, g=9.81, k=4.0, w=2.0):
        x = lambda s: -mu * g / k * (1 - np.cos(w * s)) + 0.5 / w * np.sin(w * s)  # noqa: E731
        v = lambda s: -mu * g / w * np.sin(w * s) + 0.5 * np.cos(w * s)  # noqa: E731
        t1 = 0.2 + 0j
        for _ in range(60):  # V(t1) = AB t1: Newton (A = -K X - MU G before it)
            t1 = t1 - (v(t1) - ab * t1) / (-k * x(t1) - mu * g - ab)
        return ab + k * (x(t1) + ab * (t * t - t1 * t1) / 2)

    track = trajectory(amilpy.loads(belt), 0, ["MU", "AB"], {"MU": 0.4, "AB": 1.0, "K": 4.0},
                       {}, [0.5, 0.8])
    for t in (0.5, 0.8):
        exact = [carried(0.4 + 1e-30j, 1.0, t).imag / 1e-30,
                 carried(0.4, 1.0 + 1e-30j, t).imag / 1e-30]
        assert track.row("F", t) == pytest.approx(exact, rel=1e-6), t


def test_a_fit_through_sticking_uses_the_sensitivities(tmp_path):
    """MU = 0.2 from the sliding block's X before and after it stops: recovered with
    the variational equations (the tangent through the stop)."""
    mu, g = 0.2, 9.81
    stop = 2.0 / (mu * g)
    t = np.arange(0.125, 1.5, 0.125)
    x = np.where(t < stop, 2.0 * t - 0.5 * mu * g * t ** 2, 2.0 * stop - 0.5 * mu * g * stop ** 2)
    fit = amilpy.loads(FRICTION).fit(_csv(tmp_path, "TIME,X", zip(t, x, strict=True)),
                                     ["MU=0.05:1"], weights="none", gradients="sensitivities")
    assert fit.estimates[0] == pytest.approx(mu, rel=1e-6)
    assert fit.gradients.startswith("variational equations") and fit.jacobians >= 1


def test_sensitivities_with_several_surfaces_sliding_are_the_closed_forms():
    """Two blocks stopping by dry friction (0.34 s and 0.68 s: then two surfaces slide
    at once) give X = V0^2/(2 MU G) each; two relays stuck together at the origin
    (tests/test_sliding.py: X = 0 from X0/1.5, then Y' = -1.25 until both slide) give
    d Y/d X0 = 0.75/1.5 in between; a block stuck on a belt (two friction terms on
    one surface, sliding from the start) is pushed off at K X = F1 + F2, then X =
    (F1 + F2)/K + VB sin(t - ts): its d X/d VB (which moves the surface it starts
    on: the tangent is brought back onto it) and d X/d F1, d X/d K, against the
    complex-step derivative of that closed form. All to 1e-8."""
    from test_sliding import TWO_FRICTIONS

    from amilpy.analysis.sensitivity import trajectory

    two = FRICTION.replace("OUTPUT X", "A2 = FSW(V2, MU*G, 0.0, -MU*G)\n"
                           "V2 = INTGRL(1.0, A2)\nX2 = INTGRL(0.0, V2)\nOUTPUT X")
    track = trajectory(amilpy.loads(two), 0, ["MU"], {"MU": 0.3}, {}, [0.5, 1.4])
    assert not isinstance(track, str), track
    mu, g = 0.3, 9.81
    assert track.row("X2", 0.5)[0] == pytest.approx(-0.5 / (mu * mu * g), rel=1e-8)
    assert [track.row("X", 1.4)[0], track.row("X2", 1.4)[0]] == pytest.approx(
        [-2.0 / (mu * mu * g), -0.5 / (mu * mu * g)], rel=1e-8)
    relays = """PARAM X0 = 1.0, Y0 = 1.0
SX = FSW(X, -1.0, 0.0, 1.0)
SY = FSW(Y, -1.0, 0.0, 1.0)
X = INTGRL(X0, -SX - 0.5*SY)
Y = INTGRL(Y0, -SY + 0.5*SX)
TIMER FINTIM = 2.0, OUTDEL = 0.1
END
"""
    track = trajectory(amilpy.loads(relays), 0, ["X0", "Y0"], {"X0": 1.0, "Y0": 1.0}, {},
                       [0.5, 0.9, 1.5])
    assert np.concatenate([track.row("Y", 0.9), track.row("X", 0.9)]) == pytest.approx(
        [0.5, 1.0, 0.0, 0.0], abs=1e-8)
    assert np.concatenate([track.row("X", 1.5), track.row("Y", 1.5)]) == pytest.approx(
        [0.0, 0.0, 0.0, 0.0], abs=1e-8)

    def belt(t, f1, k, vb, f2=0.2):
        ts = (f1 + f2) / (k * vb)
        w = np.sqrt(k)
        return vb * t if t < np.real(ts) else (f1 + f2) / k + vb / w * np.sin(w * (t - ts))

    values = {"K": 1.0, "F1": 0.3, "F2": 0.2, "VB": 1.0, "M": 1.0}
    track = trajectory(amilpy.loads(TWO_FRICTIONS), 0, ["F1", "K", "VB"], values, {},
                       [0.3, 0.6, 1.0, 1.5])
    for t in (0.3, 0.6, 1.0, 1.5):
        exact = [belt(t, 0.3 + 1e-30j, 1.0, 1.0).imag / 1e-30,
                 belt(t, 0.3, 1.0 + 1e-30j, 1.0).imag / 1e-30,
                 belt(t, 0.3, 1.0, 1.0 + 1e-30j).imag / 1e-30]
        assert track.row("X", t) == pytest.approx(exact, abs=1e-8), t


@pytest.mark.parametrize("text, names, values, why", [
    # a TIME switch due exactly at an observed instant (the next stretch started on
    # its surface and kept the old branch: dX/dK at 1.5 was -0.525 for -0.173)
    ("PARAM K = 0.7\nY = K*STEP(1.0)\nX = INTGRL(1.0, -K*X + Y)\n", ["K"], {"K": 0.7}, ""),
    # a value of 0 (its column was 0: moved by 0)
    ("PARAM K = 0.7, B = 0.0\nINCON X0 = 1.0\nX = INTGRL(X0, -K*X + B)\nY = K*X + 3.0*B\n",
     ["B", "X0"], {"B": 0.0, "X0": 1.0}, ""),
    # a memory function's initial value (its sensitivity was 0: not followed), a play's
    # (its memory carried on the branch the motion takes: `ProgramTangent.leaned`)
    ("PARAM K = 0.7, YIC = 1.0\nY = HSTRSS(YIC, -10.0, 10.0, X)\nX = INTGRL(0.0, -K*X + Y)\n",
     ["YIC", "K"], {"YIC": 1.0, "K": 0.7}, ""),
    # a random draw read by the derivatives, its mean and spread free (the draws are
    # the seeded stream's: the same numbers in every run), observed at draw instants
    ("PARAM K = 0.7, MU = 1.0, SD = 0.3\nY = GAUSS(MU, SD)\nX = INTGRL(0.0, -K*X + Y)\n",
     ["MU", "SD", "K"], {"MU": 1.0, "SD": 0.3, "K": 0.7}, ""),
    # CSMP's PULSE(P, X), whose end P moves (a memory that holds an instant)
    ("PARAM P = 0.3, K = 0.7\nY = PULSE(P, X - 0.4)\nX = INTGRL(0.0, 1.0 - K*X - 2.0*Y)\n",
     ["P", "K"], {"P": 0.3, "K": 0.7}, ""),
    # a hold of a state whose start is free, read after it holds (ZHOLD's memory is
    # carried through its updates)
    ("PARAM K = 0.7, YIC = 1.0\nY = YIC + ZHOLD(0.3 - TIME, X)\nX = INTGRL(YIC, -K*X)\n",
     ["YIC", "K"], {"YIC": 1.0, "K": 0.7}, ""),
])
def test_sensitivities_agree_with_differences_or_say_why_not(tmp_path, text, names, values,
                                                             why):
    from amilpy.analysis.sensitivity import observed_jacobian
    from amilpy.observed import read

    model = amilpy.loads(text + "TIMER FINTIM = 2.0, OUTDEL = 0.1\nPRINT X, Y\nEND\n")
    obs = read(_csv(tmp_path, "TIME,X,Y", [(t, 0.0, 0.0) for t in (0.5, 1.0, 1.5)]),
               model.ir.variables, 1)
    exact, said = observed_jacobian(model, obs, names, values, {}, {})
    if why:
        assert exact is None and why in said
        return

    def simulated(**kw):
        run = model.run(advice=False, data=obs, rtol=1e-12, atol=1e-15, **{**values, **kw})[0]
        return np.concatenate([c.simulated for c in run.observed])

    diff = np.column_stack([(simulated(**{n: values[n] + 1e-5}) -
                             simulated(**{n: values[n] - 1e-5})) / 2e-5 for n in names])
    assert said == "" and np.max(np.abs(exact - diff)) < 1e-6
