"""`amilpy montecarlo` / Model.montecarlo: draws from each distribution, quantile
bands against closed forms, failed runs listed, the same runs whatever the
number of workers."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from scipy import stats

import amilpy
from amilpy.batch.distributions import parse_dist, sample
from amilpy.cli import main
from amilpy.diagnostics import UsageError

DECAY = """TITLE DECAY WITH AN UNCERTAIN RATE
PARAM K = 1.0, X0 = 1.0
X = INTGRL(X0, -K*X)
TIMER FINTIM = 2.0, OUTDEL = 0.1, PRDEL = 0.5
PRINT X
OUTPUT X
END
"""


@pytest.fixture
def decay(tmp_path):
    path = tmp_path / "decay.amil"
    path.write_text(DECAY)
    return path


def test_lognormal_rate_gives_the_exact_quantiles_at_every_time(decay):
    # X(t) = exp(-K t) with ln K ~ N(0, 0.3): P(X(t) <= x) = 1 - Phi(ln(-ln(x)/t)/0.3).
    # The exact CDF at each sample quantile of 4,000 runs must be within 4 binomial
    # standard deviations, sqrt(p(1-p)/n), of p (a sample quantile's own spread;
    # the integration's error, 1e-7 of X at RELERR 1e-6, is 1e-4 of that band).
    mc = amilpy.load(decay).montecarlo({"K": "lognormal(0, 0.3)"}, runs=4000, seed=11)
    assert mc.done == 4000 and not mc.failed
    n = 4000
    for qi, q in enumerate(mc.quantiles):
        p = q / 100
        for i, t in enumerate(mc.times):
            if t == 0:
                assert mc.bands[qi, i, 0] == pytest.approx(1.0, abs=1e-15)
                continue
            x = mc.bands[qi, i, 0]
            cdf = 1.0 - stats.norm.cdf(math.log(-math.log(x) / t) / 0.3)
            assert abs(cdf - p) <= 4 * math.sqrt(p * (1 - p) / n), (q, t, cdf)
    # and the final values' quantiles are the last row's
    assert mc.final_quantiles()[:, 0] == pytest.approx(mc.bands[:, -1, 0], rel=1e-12)


def test_every_distribution_draws_what_it_names():
    # Kolmogorov-Smirnov of 4,000 draws against SciPy's distribution: p > 0.001
    # (the draws are fixed by the seed, so this either always passes or never).
    cases = {"A": ("normal(2, 0.5)", stats.norm(2, 0.5)),
             "B": ("lognormal(0.1, 0.4)", stats.lognorm(0.4, scale=math.exp(0.1))),
             "C": ("uniform(-1, 3)", stats.uniform(-1, 4)),
             "D": ("triangular(0, 1, 4)", stats.triang(0.25, loc=0, scale=4)),
             "E": ("truncnormal(1, 2, 0, 1.5)",
                   stats.truncnorm(-0.5, 0.25, loc=1, scale=2))}
    dists = {k: parse_dist(k, text) for k, (text, _) in cases.items()}
    drawn = sample(dists, 4000, seed=5)
    for name, (_, ref) in cases.items():
        assert stats.kstest(drawn[name], ref.cdf).pvalue > 1e-3, name
    assert drawn["E"].min() >= 0 and drawn["E"].max() <= 1.5
    again = sample(dists, 4000, seed=5)
    assert all(np.array_equal(drawn[k], again[k]) for k in cases)
    assert not np.array_equal(drawn["A"], sample(dists, 4000, seed=6)["A"])


def test_correlated_names_have_the_copula_rank_correlation():
    # Gaussian copula with r = 0.6: the rank correlation is 6/pi asin(r/2) = 0.5824;
    # 20,000 draws estimate it to about 0.006 (4 of that: 0.025).
    dists = {"A": parse_dist("A", "uniform(0, 1)"), "B": parse_dist("B", "lognormal(0, 1)")}
    drawn = sample(dists, 20000, seed=2, correlation={("A", "B"): 0.6})
    rho = stats.spearmanr(drawn["A"], drawn["B"])[0]
    assert rho == pytest.approx(6 / math.pi * math.asin(0.3), abs=0.025)
    with pytest.raises(UsageError, match="not positive definite"):
        three = {k: parse_dist(k, "normal(0, 1)") for k in "ABC"}
        sample(three, 10, 1, {("A", "B"): 0.9, ("B", "C"): 0.9, ("A", "C"): -0.9})


def test_a_table_gives_its_rows_in_order_and_keeps_them_together(decay, tmp_path):
    table = tmp_path / "draws.csv"
    table.write_text("K,X0\n0.5,2.0\n1.0,1.0\n2.0,0.5\n")
    mc = amilpy.load(decay).montecarlo({"K": f"table({table})", "X0": f"table({table})"})
    assert mc.runs == 3  # the table's rows
    assert mc.samples["K"].tolist() == [0.5, 1.0, 2.0]
    assert mc.samples["X0"].tolist() == [2.0, 1.0, 0.5]
    # each run's final value is X0 exp(-2 K) (RELERR 1e-6)
    assert mc.final[:, 0] == pytest.approx([2 * math.exp(-1), math.exp(-2), 0.5 * math.exp(-4)],
                                           rel=1e-5)
    with pytest.raises(UsageError, match="has 3 rows"):
        amilpy.load(decay).montecarlo({"K": f"table({table})"}, runs=4)


FAILING = """TITLE A RUN THAT CANNOT START FOR K < 1
PARAM K = 2.0
INITIAL
   R = SQRT(K - 1.0)
DYNAMIC
X = INTGRL(R, -X)
TIMER FINTIM = 1.0, OUTDEL = 0.1
PRINT X
END
"""


def test_failed_runs_are_counted_listed_and_left_out(tmp_path, capsys):
    # K uniform on (0.5, 1.5): the runs with K < 1 cannot start (SQRT of a negative
    # number: X starts at NaN). They are listed with their K, left out of the quantiles, and the
    # command exits 3; the kept runs' final values are sqrt(K - 1) e^-1.
    path = tmp_path / "fail.amil"
    path.write_text(FAILING)
    mc = amilpy.load(path).montecarlo({"K": "uniform(0.5, 1.5)"}, runs=200, seed=4)
    bad = np.flatnonzero(mc.samples["K"] < 1.0).tolist()
    assert mc.failed == bad and 60 < len(bad) < 140
    assert all("initial value of X is not finite" in mc.messages[k] for k in bad)
    kept = mc.samples["K"][mc.kept]
    assert mc.final[mc.kept, 0] == pytest.approx(np.sqrt(kept - 1) * math.exp(-1), rel=1e-5)
    assert np.all(np.isnan(mc.final[bad, 0]))
    assert mc.final_quantiles()[1, 0] == pytest.approx(
        np.median(np.sqrt(kept - 1) * math.exp(-1)), rel=1e-5)
    samples = tmp_path / "runs.csv"
    assert main(["montecarlo", str(path), "--dist", "K=uniform(0.5,1.5)", "--runs", "200",
                 "--seed", "4", "--samples", str(samples), "--jobs", "1"]) == 3
    out, err = capsys.readouterr()
    assert f"FAILED RUNS ({len(bad)}" in out and f"run {bad[0] + 1}: K = " in out
    assert f"{len(bad)} of 200 runs failed" in err
    with open(samples, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["RUN", "STATUS", "K", "FINAL_X", "MESSAGE"]
    assert [int(r[0]) - 1 for r in rows[1:] if r[1] == "failed"] == bad


def test_the_bands_are_the_same_taken_a_few_rows_at_a_time(tmp_path, monkeypatch):
    # The bands are sorted a block of output rows at a time (a 10,000-member hoist
    # would otherwise copy its whole cube twice): blocks of a few values, with failed
    # runs left out (their rows NaN), give the same bands and counts bit for bit and
    # the same means to rounding (NumPy sums a block in another order).
    from amilpy.batch import montecarlo

    path = tmp_path / "fail.amil"
    path.write_text(FAILING)
    whole = amilpy.load(path).montecarlo({"K": "uniform(0.5, 1.5)"}, runs=40, seed=4)
    monkeypatch.setattr(montecarlo, "BLOCK_VALUES", 7)
    blocks = amilpy.load(path).montecarlo({"K": "uniform(0.5, 1.5)"}, runs=40, seed=4)
    assert whole.failed and np.array_equal(whole.bands, blocks.bands, equal_nan=True)
    assert blocks.mean == pytest.approx(whole.mean, rel=1e-15, abs=0.0)
    assert np.array_equal(whole.counts, blocks.counts)


def test_the_same_runs_whatever_the_workers(decay):
    model = amilpy.load(decay)
    one = model.montecarlo({"K": "lognormal(0, 0.3)", "X0": "normal(1, 0.1)"}, runs=300,
                           seed=8, jobs=1)
    two = amilpy.load(decay).montecarlo({"K": "lognormal(0, 0.3)", "X0": "normal(1, 0.1)"},
                                        runs=300, seed=8, jobs=2)
    assert np.array_equal(one.bands, two.bands) and np.array_equal(one.final, two.final)
    assert all(np.array_equal(one.samples[k], two.samples[k]) for k in one.samples)


def test_montecarlo_writes_bands_samples_and_figures(decay, tmp_path, capsys):
    bands, runs = tmp_path / "bands.csv", tmp_path / "runs.csv"
    code = main(["montecarlo", str(decay), "--dist", "K=lognormal(0,0.3)", "--runs", "50",
                 "--quantiles", "10,25,50,75,90", "--csv", str(bands), "--samples",
                 str(runs), "--plot", "--out", str(tmp_path), "--jobs", "1"])
    assert code == 0
    out = capsys.readouterr().out
    assert out.startswith("MONTE CARLO OF DECAY WITH AN UNCERTAIN RATE")
    assert "X: QUANTILES OVER THE RUNS AT THE PRDEL INSTANTS" in out
    with open(bands, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["TIME", "X_MEAN", "X_P10", "X_P25", "X_P50", "X_P75", "X_P90", "RUNS"]
    assert len(rows) == 22 and rows[-1][-1] == "50"
    p10, p90 = float(rows[-1][2]), float(rows[-1][6])
    assert p10 < float(rows[-1][4]) < p90
    assert (tmp_path / "decay_montecarlo_1.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("argv, message", [
    (["--dist", "K=gauss(1,2)", "--runs", "5"], "'gauss' is no distribution"),
    (["--dist", "K=normal(1)", "--runs", "5"], "normal takes 2 numbers"),
    (["--dist", "K=normal(1,-2)", "--runs", "5"], "needs mean m, standard deviation s > 0"),
    (["--dist", "K=uniform(2,1)", "--runs", "5"], "needs a < b"),
    (["--dist", "Q=uniform(0,1)", "--runs", "5"], "Q: not a PARAM/CONST/INCON"),
    (["--dist", "K=uniform(0,1)"], "give the number of runs"),
    (["--dist", "K=uniform(0,1)", "--runs", "5", "--set", "K=2"], "both --set and --dist"),
    (["--dist", "K=uniform(0,1)", "--runs", "5", "--correlate", "K,X0=0.5"],
     "X0 has no --dist"),
    (["--dist", "K=uniform(0,1)", "--runs", "5", "--quantiles", "5,150"], "between 0 and 100"),
    (["--dist", "K=uniform(0,1)", "--runs", "5", "--seed", "1.5"], "whole number"),
])
def test_montecarlo_usage_errors(decay, capsys, argv, message):
    assert main(["montecarlo", str(decay), *argv]) == 2
    assert message in capsys.readouterr().err


TWO_COMPARTMENTS = """TITLE INFUSION INTO TWO COMPARTMENTS
PARAM RATE = 10.0, K12 = 0.5, K21 = 0.3, KE = 0.2, V1 = 5.0
INITIAL
   KT = K12 + KE
DYNAMIC
A1 = INTGRL(0.0, RATE - KT*A1 + K21*A2)
A2 = INTGRL(0.0, K12*A1 - K21*A2)
C1 = A1/V1
TIMER FINTIM = 24.0, OUTDEL = 0.5, PRDEL = 4.0
PRINT C1, A2
END
"""


def test_an_ensemble_that_shares_its_instants_is_integrated_at_once(tmp_path):
    # No member switches on its own: the runs are one stacked LSODA integration.
    # Member by member and stacked agree to the tolerances' order (RELERR 1e-6 by
    # default here, the stacked error test being each member's own: 1e-5 relative),
    # and both match the closed form of the linear system (expm of its matrix,
    # integrated input) to 1e-5.
    from scipy.linalg import expm

    path = tmp_path / "two.amil"
    path.write_text(TWO_COMPARTMENTS)
    dists = {"KE": "lognormal(-1.6, 0.3)", "K12": "uniform(0.3, 0.7)"}
    model = amilpy.load(path)
    together = model.montecarlo(dists, runs=300, seed=2, outputs=["C1", "A2"])
    one_by_one = amilpy.load(path).montecarlo(dists, runs=300, seed=2, outputs=["C1", "A2"],
                                              stacked=False)
    assert np.array_equal(together.samples["KE"], one_by_one.samples["KE"])
    assert together.final == pytest.approx(one_by_one.final, rel=1e-5)
    assert together.bands == pytest.approx(one_by_one.bands, rel=1e-5, abs=1e-9)
    for k in (0, 137, 299):
        ke, k12 = together.samples["KE"][k], together.samples["K12"][k]
        a = np.array([[-(k12 + ke), 0.3], [k12, -0.3]])
        # x(T) = A^-1 (e^{AT} - I) b for x' = A x + b, x(0) = 0
        x = np.linalg.solve(a, (expm(24.0 * a) - np.eye(2)) @ np.array([10.0, 0.0]))
        assert together.final[k] == pytest.approx([x[0] / 5.0, x[1]], rel=1e-5)


def test_members_that_switch_on_their_own_run_one_by_one(decay, tmp_path):
    # A switch whose instant depends on a drawn value: the stacked route declines
    # (each member would switch at its own instant), and the runs are the plain ones.
    from amilpy.batch import stacked
    from amilpy.run import Options, prepare

    path = tmp_path / "switch.amil"
    path.write_text("PARAM TS = 0.5\nX = INTGRL(0.0, INSW(TIME - TS, 0.0, 1.0))\n"
                    "TIMER FINTIM = 1.0, OUTDEL = 0.1\nPRINT X\nEND\n")
    model = amilpy.load(path)
    prepared = prepare(model.ir, model.ir.runs[0], Options(), model.cache)
    assert "their own instants" in stacked.why_not(model, prepared.code, prepared.plan,
                                                   Options())
    mc = model.montecarlo({"TS": "uniform(0.2, 0.8)"}, runs=20, seed=1)
    assert mc.final[:, 0] == pytest.approx(1.0 - mc.samples["TS"], abs=1e-9)


def test_when_every_run_fails_the_runs_are_listed(tmp_path, capsys):
    path = tmp_path / "fail.amil"
    path.write_text(FAILING)
    assert main(["montecarlo", str(path), "--dist", "K=uniform(0.1,0.5)", "--runs", "3",
                 "--jobs", "1"]) == 3
    out = capsys.readouterr().out
    assert "3 run, 0 kept, 3 failed" in out and "FAILED RUNS (3" in out


@pytest.mark.parametrize("argv, message", [
    (["--dist", "K=normal(1,0.1)", "--dist", "K=normal(2,0.1)", "--runs", "3"],
     "K has two distributions"),
    (["--dist", "K=normal(1,0.1)", "--dist", "X0=normal(1,0.1)", "--runs", "3",
      "--correlate", "K,X0=0.5", "--correlate", "X0,K=-0.5"], "given twice"),
])
def test_a_value_or_pair_given_twice_is_refused(decay, capsys, argv, message):
    assert main(["montecarlo", str(decay), *argv]) == 2
    assert message in capsys.readouterr().err


def test_the_api_checks_what_the_command_line_checks(decay):
    model = amilpy.load(decay)
    with pytest.raises(UsageError, match="between 0 and 100"):
        model.montecarlo({"K": "uniform(0, 1)"}, runs=3, quantiles=(150,))
    with pytest.raises(UsageError, match="whole number"):
        model.montecarlo({"K": "uniform(0, 1)"}, runs=2.7)
    with pytest.raises(UsageError, match="two names"):
        model.montecarlo({"K": "uniform(0, 1)"}, runs=3, correlation={"K": 0.5})


def test_step_point_mode_is_the_runs_own(tmp_path):
    # --step-point reaches every member: the Monte Carlo of one fixed value is the run.
    path = tmp_path / "rect.amil"
    path.write_text("PARAM K = 1.0\nX = INTGRL(1.0, -K*X)\nMETHOD RKS\n"
                    "TIMER FINTIM = 1.0, OUTDEL = 0.1, DELT = 0.1\nPRINT X\nEND\n")
    model = amilpy.load(path)
    run, = model.run(method="EULER", step_point=True)
    mc = model.montecarlo({"K": "uniform(0.999999999, 1.000000001)"}, runs=2, seed=1,
                          method="EULER", step_point=True)
    assert mc.final[:, 0] == pytest.approx([run["X"][-1]] * 2, rel=1e-8)
    assert run["X"][-1] == pytest.approx(0.9 ** 10, rel=1e-12)


def test_an_output_into_the_listing_itself_is_refused(decay, capsys):
    text = decay.read_text()
    assert main(["montecarlo", str(decay), "--dist", "K=uniform(0.5,1.5)", "--runs", "2",
                 "--csv", str(decay)]) == 2
    assert "is the listing itself" in capsys.readouterr().err
    assert decay.read_text() == text
    assert main(["run", str(decay), "--csv", str(decay)]) == 2
    assert decay.read_text() == text


DOSING = """PROGRAM repeated oral doses, a drawn elimination rate and volume
  CONSTANT DOSE = 500.0, KA = 1.2, KE = 0.173, VD = 42.0, TSTOP = {tstop}
  CINTERVAL CINT = 0.5
  {timer}
  INITIAL
    NDOSE = 0.0
  END
  DERIVATIVE
    AG = INTEG(-KA*AG, 0.0)
    AB = INTEG(KA*AG - KE*AB, 0.0)
    CP = AB/VD
    TERMT(T >= TSTOP, 'end of the regimen')
  END
  DISCRETE DOSE
    INTERVAL DTDOSE = 12.0
    {dose}
    NDOSE = NDOSE + 1.0
  END
  TERMINAL
    CLAST = CP
  END
  PRINT CP, AG, NDOSE
END
"""


def dosing(tmp_path, tstop="72.0", timer="", dose="AG = AG + DOSE"):
    path = tmp_path / "dosing.csl"
    path.write_text(DOSING.format(tstop=tstop, timer=timer, dose=dose))
    return path


def bateman(t: float, ke: float, vd: float, doses) -> float:
    """CP of one-compartment oral dosing: one Bateman curve per dose given by t."""
    ka, d = 1.2, 500.0
    return sum(d * ka / (ka - ke) * (math.exp(-ke * (t - tk)) - math.exp(-ka * (t - tk)))
               for tk in doses if tk <= t + 1e-9) / vd


def at_once_and_alone(path, dists, runs, seed, rel=1e-9):
    """The Monte Carlo integrated at once and its runs one by one, which must give
    the same rows and bands (to `rel`: both at the listing's tolerances)."""
    together = amilpy.load(path).montecarlo(dists, runs=runs, seed=seed)
    alone = amilpy.load(path).montecarlo(dists, runs=runs, seed=seed, stacked=False)
    assert "at once" in together.how and "at once" not in alone.how
    assert np.array_equal(together.times, alone.times)
    assert together.bands == pytest.approx(alone.bands, rel=rel, abs=1e-12)
    assert together.final == pytest.approx(alone.final, rel=rel)
    return together, alone


def test_acsl_members_dosed_at_the_same_instants_are_integrated_at_once(tmp_path):
    # The doses come every 12 h for every member and the TERMT is on TIME alone, so
    # the members share their instants: one stacked integration from dose to dose,
    # the DISCRETE and TERMINAL code run on the members' columns. Each member is
    # the superposition of Bateman curves (7 doses, the one at TSTOP given before
    # the run ends) to the ACSL form's default tolerances (RELERR 1e-11 here: 1e-9
    # relative allows for 72 h of accumulation), and the same, row by row, as the
    # members run one by one (both at those tolerances: 1e-9).
    dists = {"KE": "lognormal(-1.754, 0.25)", "VD": "lognormal(3.738, 0.2)"}
    path = dosing(tmp_path)
    together, alone = at_once_and_alone(path, dists, 60, 4)
    assert together.terminal == pytest.approx(alone.terminal, rel=1e-9)
    assert together.status == alone.status == ["stopped"] * 60
    assert together.messages == alone.messages
    doses = [12.0 * k for k in range(7)]
    for k in (0, 17, 59):
        ke, vd = together.samples["KE"][k], together.samples["VD"][k]
        cp, ag, ndose = together.final[k]
        assert cp == pytest.approx(bateman(72.0, ke, vd, doses), rel=1e-9)
        assert ndose == 7.0 and together.terminal[k, 0] == cp
    median = together.band("CP")[together.quantiles.index(50.0)]
    assert median[-1] == pytest.approx(np.median(together.final[:, 0]), rel=1e-12)


@pytest.mark.parametrize("tstop, timer", [
    ("71.3", ""),  # the TERMT instant between two rows: the run's last row is there
    ("1000.0", "TIMER FINTIM = 30.25"),  # the end of the run, not a TERMT
])
def test_acsl_members_at_once_end_where_each_run_ends(tmp_path, tstop, timer):
    dists = {"KE": "uniform(0.1, 0.25)"}
    path = dosing(tmp_path, tstop, timer)
    together, alone = at_once_and_alone(path, dists, 8, 2)
    assert np.array_equal(together.prdel, alone.prdel)
    assert together.status == alone.status and together.messages == alone.messages


def test_acsl_code_that_branches_on_a_members_value_runs_member_by_member(tmp_path):
    # A dose skipped while the body holds more than 300 mg: the branch cannot run on
    # the members' columns, so the DISCRETE section runs member by member (each
    # with its own functions) at the instants they all share, between which the
    # members are still integrated at once. Some members skip doses, some do not.
    dists = {"KE": "uniform(0.05, 0.3)"}
    path = dosing(tmp_path, dose="IF (AB .LT. 300.0) AG = AG + DOSE")
    together, alone = at_once_and_alone(path, dists, 10, 3)
    ndose = together.final[:, together.variables.index("NDOSE")]
    assert len(set(ndose)) == 1 and ndose[0] == 7.0  # (NDOSE counts the section's runs)
    ag = together.final[:, together.variables.index("AG")]
    assert np.any(ag < 1.0) and np.any(ag > 400.0)  # (the dose at 72 h skipped or given)


@pytest.mark.parametrize("dists, where, instead", [
    # a drawn stop moves each member's TERMT instant
    ({"TSTOP": "uniform(60, 70)"}, "", ""),
    # an extra dose SCHEDULEd by INITIAL at an instant of each member's own
    ({"KE": "uniform(0.1, 0.25)"}, "NDOSE = 0.0", "NDOSE = 0.0\n    SCHEDULE DOSE .AT. 40.0*KE"),
])
def test_acsl_members_with_instants_of_their_own_run_one_by_one(tmp_path, dists, where,
                                                                 instead):
    # The stacked route declines; the runs are the plain ones, still right.
    path = dosing(tmp_path)
    path.write_text(path.read_text().replace(where, instead) if where else path.read_text())
    mc = amilpy.load(path).montecarlo(dists, runs=6, seed=3)
    assert "at once" not in mc.how
    for k in range(6):
        run, = amilpy.load(path).run(advice=False, **mc.values_of(k))
        assert mc.final[k] == pytest.approx([run.final[n] for n in mc.variables], rel=1e-12)


def test_a_large_ensemble_is_integrated_in_parts(tmp_path, monkeypatch):
    # LSODA allocates the square of its equations (its stiff method's matrix): an
    # ensemble of more states than MAX_EQUATIONS goes in parts, each held to the
    # same tolerances (1e-9 relative, the default RELERR 1e-11 over 72 h).
    from amilpy.batch import stacked

    dists = {"KE": "uniform(0.1, 0.25)"}
    path = dosing(tmp_path)
    whole = amilpy.load(path).montecarlo(dists, runs=12, seed=5)
    monkeypatch.setattr(stacked, "MAX_EQUATIONS", 10)  # 5 members of 2 states a part
    parts = amilpy.load(path).montecarlo(dists, runs=12, seed=5)
    assert "in 3 parts of 5" in parts.how and "parts" not in whole.how
    assert parts.final == pytest.approx(whole.final, rel=1e-9)
    assert parts.bands == pytest.approx(whole.bands, rel=1e-9, abs=1e-12)


CLEARANCE = """PROGRAM elimination through two FUNCTIONs
  CONSTANT VMAX = 8.0, KM = 2.0, VD = 10.0, TSTOP = 24.0
  CINTERVAL CINT = 1.0
  FUNCTION R = MM(C, V, K)
    R = V*C/(K + C)
  END
  FUNCTION F = FLOOR0(X)
    IF (X < 0.0) THEN
      F = 0.0
    ELSE
      F = X
    END IF
  END
  DERIVATIVE
    A = INTEG(-MM(FLOOR0(A/VD), VMAX, KM), 100.0)
    TERMT(T >= TSTOP)
  END
  PRINT A
END
"""


def test_an_ensembles_functions_run_on_its_columns(tmp_path):
    # MM is plain arithmetic: it runs on the members' columns as written; FLOOR0
    # branches on its argument (an IF statement), so on columns it runs element by
    # element. Either way the members, integrated at once, are the runs one by one
    # (to 1e-9: RELERR 1e-11 over 24 h), and each member's A is the implicit
    # closed form of Michaelis-Menten elimination:
    # VD (C0 - C) + KM VD ln(C0 / C) = VMAX t, with C = A / VD.
    path = tmp_path / "clearance.csl"
    path.write_text(CLEARANCE)
    dists = {"VMAX": "uniform(6, 10)"}
    together, alone = at_once_and_alone(path, dists, 12, 7)
    for k in range(12):
        c, c0, vmax = together.final[k, 0] / 10.0, 10.0, together.samples["VMAX"][k]
        assert 10.0 * (c0 - c) + 2.0 * 10.0 * math.log(c0 / c) == \
            pytest.approx(vmax * 24.0, rel=1e-9)


STIFF = """PROGRAM a dose into two compartments that exchange fast (stiff)
  CONSTANT K12 = 2000.0, K21 = 1000.0, KE = 0.3, DOSE = 90.0
  CINTERVAL CINT = 0.25
  DERIVATIVE
    A1 = INTEG(-K12*A1 + K21*A2 - KE*A1, 0.0)
    A2 = INTEG(K12*A1 - K21*A2, 0.0)
    TERMT(T >= 6.0)
  END
  DISCRETE DOSE
    INTERVAL DTDOSE = 3.0
    A1 = A1 + DOSE
  END
  PRINT A1, A2
END
"""


def test_stiff_members_at_once_take_their_jacobian_from_the_equations(tmp_path):
    # Exchange at 3000/h against elimination at 0.3/h: LSODA's stiff method, with
    # each member's Jacobian block from the model's equations (the stacked system's
    # band). Each member is the closed form of the linear system, dose by dose
    # (expm; 1e-8 relative: RELERR 1e-11 over 2 doses), and the runs one by one.
    from scipy.linalg import expm

    path = tmp_path / "stiff.csl"
    path.write_text(STIFF)
    dists = {"KE": "uniform(0.1, 0.5)", "K12": "uniform(1500, 2500)"}
    together, _ = at_once_and_alone(path, dists, 16, 8, rel=1e-8)
    for k in (0, 9, 15):
        ke, k12 = together.samples["KE"][k], together.samples["K12"][k]
        a = np.array([[-k12 - ke, 1000.0], [k12, -1000.0]])
        x = np.zeros(2)
        for _ in range(2):  # doses at 0 and 3 h (the one at 6 h given before the end)
            x = expm(3.0 * a) @ (x + [90.0, 0.0])
        x += [90.0, 0.0]
        assert together.final[k] == pytest.approx(x, rel=1e-8)


@pytest.mark.parametrize("jacobian", ["equations", "not finite", "none"])
def test_stacked_lsoda_on_a_stiff_linear_ensemble(jacobian):
    # y' = A_k y for every member k, A_k stiff (eigenvalues -1 and -1e4 k): each
    # member's exp(A_k t) y0 to 1e-8 relative whether the Jacobian blocks come from
    # the equations, from differences (where the equations' entries are not finite,
    # each state of every member moved at once), or from LSODA's own band.
    from scipy.linalg import expm

    from amilpy.batch.stacked import lsoda
    from amilpy.codegen.jacobian import ModelJacobian
    from amilpy.run.plan import Tolerances

    runs = 5
    scale = np.linspace(1.0, 3.0, runs)
    a11, a12, a21, a22 = -1e4 * scale, 1e4 * scale - 1.0, 0.0 * scale, -1.0 + 0.0 * scale

    def rhs(t, cols):
        return [a11 * cols[0] + a12 * cols[1], a21 * cols[0] + a22 * cols[1]]

    entries = {"equations": lambda t, cols: [a11, a12],
               "not finite": lambda t, cols: [a11 * np.nan, a12]}
    jac = None if jacobian == "none" else ModelJacobian(
        2, np.array([0, 0, 1]), np.array([0, 1, 1]), np.array([np.nan, np.nan, -1.0]),
        entries[jacobian], None)

    class Plan:
        max_step = math.inf
        tol = Tolerances(np.full(2, 1e-11), np.full(2, 1e-14), 1e-11, 1e-14, {}, {})

    y0 = np.tile([[1.0], [2.0]], runs)
    ts = np.array([0.0, 0.5, 2.0])
    ys, steps = lsoda(rhs, y0, ts, Plan, jac)
    assert steps > 0
    for k in range(runs):
        a = np.array([[a11[k], a12[k]], [a21[k], a22[k]]])
        for i, t in enumerate(ts):
            assert ys[i, :, k] == pytest.approx(expm(t * a) @ [1.0, 2.0], rel=1e-8)


def chain_listing(order: list[int], k: float = 500.0) -> str:
    """A stiff chain of compartments A1 -> A2 -> ... (rate K between neighbours,
    elimination KE from the last), written in `order`: written out of order, the
    Jacobian's band is wide until the states are renumbered."""
    n = len(order)
    lines = []
    for i in order:
        inflow = f" + K*A{i - 1}" if i > 1 else ""
        out = "KE" if i == n else "K"
        lines.append(f"    A{i} = INTEG(-{out}*A{i}{inflow}, {1.0 if i == 1 else 0.0})")
    return (f"PROGRAM chain\n  CONSTANT K = {k}, KE = 0.5\n  CINTERVAL CINT = 0.5\n"
            "  DERIVATIVE\n" + "\n".join(lines) + "\n    TERMT(T >= 2.0)\n  END\n"
            f"  PRINT A{n}\nEND\n")


def test_members_states_are_renumbered_to_narrow_their_band(tmp_path):
    # Twelve compartments written in a scrambled order: each member's block, in
    # that order, spans most of its width; renumbered (reverse Cuthill-McKee) it is
    # tridiagonal. The stiff chain (rates 500/h against 0.5/h) is integrated at once
    # and matches each member's closed form (expm, 1e-8 relative) and the runs.
    from scipy.linalg import expm

    from amilpy.codegen.jacobian import for_compiled
    from amilpy.run.acsl import prepare_acsl
    from amilpy.steppers.jacobian import _band, narrowest

    order = [1, 7, 12, 2, 8, 3, 11, 9, 4, 10, 5, 6]
    path = tmp_path / "chain.csl"
    path.write_text(chain_listing(order))
    model = amilpy.load(path)
    jac = for_compiled(prepare_acsl(model.ir, model.ir.runs[0]).code)
    new, lower, upper = narrowest(12, jac.rows, jac.cols, always=True)
    assert sum(_band(jac.rows, jac.cols)) > 8 and lower + upper <= 2
    dists = {"KE": "uniform(0.2, 0.8)"}
    together = model.montecarlo(dists, runs=10, seed=4)
    alone = amilpy.load(path).montecarlo(dists, runs=10, seed=4, stacked=False)
    assert "at once" in together.how
    assert together.bands == pytest.approx(alone.bands, rel=1e-8, abs=1e-12)
    for k in (0, 5, 9):
        a = np.diag([-500.0] * 11 + [-together.samples["KE"][k]]) + np.diag([500.0] * 11, -1)
        x = expm(2.0 * a) @ np.eye(12)[0]
        assert together.final[k, 0] == pytest.approx(x[11], rel=1e-8)


SAMPLED = """PROGRAM a sampled-data controller: U set every CINT, held between
  CONSTANT K = 1.0, G = 0.5, TSTOP = 2.0
  CINTERVAL CINT = 0.1
  DYNAMIC
    U = -G*X
  END
  DERIVATIVE
    X = INTEG(-K*X + U + 1.0, 1.0)
    TERMT(T >= TSTOP)
  END
  PRINT X, U
END
"""


def test_acsl_dynamic_statements_run_on_the_members_at_every_cint(tmp_path):
    # DYNAMIC's statements run at every CINT instant (the integration goes from one
    # to the next); U held between them makes each member's X the exact recurrence
    # x' = e^{-K h} x + (1 - e^{-K h}) (u + 1) / K, u = -G x, h = CINT (1e-9
    # relative: RELERR 1e-11 over 20 intervals), and the same as one by one.
    path = tmp_path / "sampled.csl"
    path.write_text(SAMPLED)
    dists = {"K": "uniform(0.5, 2.0)", "G": "uniform(0.1, 1.0)"}
    together, alone = at_once_and_alone(path, dists, 12, 6)
    for k in (0, 6, 11):
        kk, g = together.samples["K"][k], together.samples["G"][k]
        x, decay = 1.0, math.exp(-kk * 0.1)
        for _ in range(20):
            x = decay * x + (1.0 - decay) * (1.0 - g * x) / kk
        assert together.final[k, 0] == pytest.approx(x, rel=1e-9)


TICKS = """PROGRAM a tick every CINT: the instants gather rounding (0.1 + 0.1 + ...)
  CONSTANT K = 1.0, TSTOP = 2.0
  CINTERVAL CINT = 0.1
  INITIAL
    N = 0.0
  END
  DERIVATIVE
    X = INTEG(-K*X + N, 1.0)
    TERMT(T >= TSTOP)
  END
  DISCRETE TICK
    INTERVAL DT = 0.1
    N = N + 0.1
  END
  PRINT X, N
END
"""


def test_instants_a_few_floats_from_the_grid_are_taken_as_a_run_takes_them(tmp_path):
    # The ticks fall at sums of 0.1, some a float before a grid instant (0.7999...),
    # some a float after (1.5000...2), and one after the TERMT's instant (2.0000...4):
    # a row a float from a tick is the tick's instant's row, after the tick (a run of
    # its own held it so one step at a time, and took it before the tick where odeint
    # gave the rows in a block), rows print the grid's instants, and the TERMT ends
    # the run before a tick just after it -- the same rows and values either way.
    path = tmp_path / "ticks.csl"
    path.write_text(TICKS)
    together, _ = at_once_and_alone(path, {"K": "uniform(0.5, 1.5)"}, 4, 1)
    assert together.times[8] == 0.8 and together.times[15] == 1.5
    n = together.band("N")[together.quantiles.index(50.0)]
    assert n[8] == pytest.approx(0.9) and n[15] == pytest.approx(1.6)  # (after the ticks)
    assert together.final[0, 1] == pytest.approx(2.0)  # (20 ticks: 0 ... 1.9)


FAULTS = """PROGRAM a DISCRETE section that faults for K = 1
  CONSTANT K = 2.0, TSTOP = 2.0
  CINTERVAL CINT = 0.25
  INITIAL
    Q = 0.0
  END
  DERIVATIVE
    X = INTEG(-K*X, 1.0)
    TERMT(T >= TSTOP)
  END
  DISCRETE S
    INTERVAL DT = 0.5
    Q = 1.0/(K - 1.0)
  END
  PRINT X
END
"""


def test_a_member_whose_code_faults_fails_as_its_own_run_does(tmp_path):
    # On the members' columns 1/(K - 1) would be inf for K = 1 and nothing would say
    # so: the ensemble runs one by one, and that member fails with the fault's words.
    path = tmp_path / "faults.csl"
    path.write_text(FAULTS)
    table = tmp_path / "k.csv"
    table.write_text("K\n0.5\n1.0\n1.5\n")
    mc = amilpy.load(path).montecarlo({"K": f"table({table})"})
    assert "at once" not in mc.how and mc.failed == [1]
    assert "Q (line 13): division by zero" in mc.messages[1]
    assert mc.status[0] == mc.status[2] == "stopped"


def test_initial_that_may_assign_a_drawn_value_runs_for_each_member(tmp_path):
    # INITIAL could assign K (not with FLAG = 0): each member keeps its own K.
    path = tmp_path / "flag.csl"
    path.write_text("""PROGRAM INITIAL may assign a drawn constant
  CONSTANT K = 1.0, FLAG = 0.0, TSTOP = 2.0
  CINTERVAL CINT = 0.5
  INITIAL
    IF (FLAG > 0.5) K = 2.0
  END
  DERIVATIVE
    X = INTEG(-K*X, 1.0)
    TERMT(T >= TSTOP)
  END
  PRINT X
END
""")
    together, _ = at_once_and_alone(path, {"K": "uniform(0.5, 1.5)"}, 5, 2)
    assert together.final[:, 0] == pytest.approx(np.exp(-2.0 * together.samples["K"]),
                                                  rel=1e-9)


def test_a_step_limit_is_each_members_own(tmp_path):
    # max_steps bounds each run: the members run one by one, each failing at it.
    path = dosing(tmp_path)
    mc = amilpy.load(path).montecarlo({"KE": "uniform(0.1, 0.25)"}, runs=3, seed=1,
                                      max_steps=30)
    assert "at once" not in mc.how and mc.failed == [0, 1, 2]
    assert all("more than 30 steps" in text for text in mc.messages)
