"""The random functions of section 12: GAUSS(M, S), UNIF(A, B), CSMP's GAUSS(SEED, M, S)
and RNDGEN(SEED), and the Ornstein-Uhlenbeck process OU(TC, M, S).

One stream per call site, seeded by --seed / seed= (else the listing's RNSEED, else
1): runs are reproducible bit for bit, and the sites are independent. A draw is held
for one output interval (one DELT with a fixed step), so the integral of a drawn
value is the sum of the draws times the interval, exactly. The statistics are
checked on fixed seeds, so these tests are deterministic; their bounds are five
standard errors of the estimate (a failure is a real fault, not bad luck).
"""

import math

import numpy as np
import pytest
from conftest import run1
from scipy import stats

import amilpy
from amilpy.diagnostics import AmilError
from amilpy.library.runtime import normal_draw


def listing(body: str, fintim: float = 10.0, outdel: float = 0.1, extra: str = "") -> str:
    return f"{body}\nTIMER FINTIM = {fintim}, OUTDEL = {outdel}{extra}\nEND\n"


GAUSS = listing("G = GAUSS(1.0, 2.0)\nU = UNIF(-1.0, 3.0)\nX = INTGRL(0.0, G)")


def test_same_seed_same_run_bit_for_bit():
    model = amilpy.loads(GAUSS)
    a, b = model.run(seed=7)[0], model.run(seed=7)[0]
    assert all(np.array_equal(a[n], b[n]) for n in ("G", "U", "X"))
    c = model.run(seed=8)[0]
    assert not np.array_equal(a["G"], c["G"])
    # the default seed is 1, and a listing's RNSEED seeds it when no seed is given
    assert np.array_equal(model.run()[0]["G"], model.run(seed=1)[0]["G"])
    seeded = amilpy.loads("PARAM RNSEED = 7\n" + GAUSS)
    assert np.array_equal(seeded.run()[0]["G"], a["G"])
    assert np.array_equal(seeded.run(seed=8)[0]["G"], c["G"])


@pytest.mark.parametrize("method", ["AUTO", "RKS", "RADAU"])
def test_a_draw_is_held_for_an_output_interval(method):
    """Variable step: a new draw at every output instant, held until the next; the
    run restarts there, so INTGRL of it is the sum of the draws times OUTDEL (to
    rounding), whatever the method."""
    r = run1(GAUSS, method=method, seed=3)
    g = r["G"]
    expect = np.concatenate([[0.0], np.cumsum(g[:-1]) * 0.1])
    assert np.max(np.abs(r["X"] - expect)) <= 1e-12 * max(1.0, np.max(np.abs(expect)))
    assert len(set(g)) == len(g)  # each row its own draw


def test_with_a_fixed_step_a_draw_is_held_for_delt():
    """RK4 with DELT = OUTDEL/4: four draws per output interval. The draws are the
    stream's own (site 0, seed 5): normal_draw(5, 0, 0, k), held on [k*DELT, (k+1)*DELT)."""
    r = run1(listing("G = GAUSS(0.0, 1.0)\nX = INTGRL(0.0, G)", fintim=2.0,
                     extra=", DELT = 0.025"), method="RK4", seed=5)
    draws = np.array([normal_draw(5.0, 0, 0.0, k) for k in range(80)])
    assert np.array_equal(r["G"][:-1], draws[::4])
    expect = np.concatenate([[0.0], np.cumsum(draws)]) * 0.025
    assert np.max(np.abs(r["X"] - expect[::4])) <= 1e-13


def test_in_step_point_mode_a_draw_is_held_for_a_step():
    r = run1(listing("G = GAUSS(0.0, 1.0)\nX = INTGRL(0.0, G)", fintim=1.0,
                     extra=", DELT = 0.1\nMETHOD EULER"), seed=5)
    draws = [normal_draw(5.0, 0, 0.0, k) for k in range(11)]
    assert list(r["G"]) == draws
    x = [0.0]
    for d in draws[:-1]:
        x.append(x[-1] + 0.1 * d)
    assert np.max(np.abs(r["X"] - np.array(x))) <= 1e-15


def test_gauss_and_unif_distributions():
    """5001 draws of each: mean, standard deviation and the Kolmogorov-Smirnov
    distance to the exact distribution."""
    r = run1(listing("G = GAUSS(1.0, 2.0)\nU = UNIF(-1.0, 3.0)", fintim=500.0), seed=11)
    g, u = r["G"], r["U"]
    n = len(g)
    assert abs(np.mean(g) - 1.0) <= 5 * 2.0 / math.sqrt(n)
    assert abs(np.std(g) - 2.0) <= 5 * 2.0 / math.sqrt(2 * n)
    assert stats.kstest(g, "norm", args=(1.0, 2.0)).pvalue > 1e-4
    assert -1.0 <= u.min() and u.max() < 3.0
    assert stats.kstest(u, "uniform", args=(-1.0, 4.0)).pvalue > 1e-4


def test_call_sites_are_independent_streams():
    """Two sites with the same arguments: uncorrelated (|r| within 5/sqrt(n)), and the
    CSMP forms' own seeds pick further streams."""
    r = run1(listing("A = GAUSS(0.0, 1.0)\nB = GAUSS(0.0, 1.0)\nC = GAUSS(4.0, 0.0, 1.0)\n"
                     "D = GAUSS(5.0, 0.0, 1.0)\nR = RNDGEN(4.0)", fintim=500.0))
    n = len(r["A"])
    names = ("A", "B", "C", "D")
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            assert abs(np.corrcoef(r[a], r[b])[0, 1]) <= 5 / math.sqrt(n), (a, b)
    assert 0.0 < r["R"].min() and r["R"].max() < 1.0
    assert stats.kstest(r["R"], "uniform").pvalue > 1e-4


OU_SITES = 40


def test_ornstein_uhlenbeck_mean_and_variance_over_many_seeds():
    """OU(TC, M, S) from y(t0) = M: y(t) is normal with mean M and variance
    S**2 (1 - exp(-2t/TC)), exactly, at every draw instant. 40 sites x 25 seeds =
    1000 samples per instant; mean within 5 standard errors, variance within 5 of
    its own (sqrt(2/n) relative); and the lag-one correlation of a stationary path
    is exp(-OUTDEL/TC)."""
    tc, m, s = 0.5, 3.0, 0.8
    body = "\n".join(f"Y{i} = OU({tc}, {m}, {s})" for i in range(OU_SITES))
    model = amilpy.loads(listing(body, fintim=3.0))
    runs = [model.run(seed=seed)[0] for seed in range(25)]
    t = runs[0].t
    samples = np.array([r[f"Y{i}"] for r in runs for i in range(OU_SITES)])
    n = len(samples)
    assert np.all(samples[:, 0] == m)
    for k in (1, 5, 30):
        var = s * s * (1.0 - math.exp(-2.0 * t[k] / tc))
        assert abs(np.mean(samples[:, k]) - m) <= 5 * math.sqrt(var / n)
        assert abs(np.var(samples[:, k]) / var - 1.0) <= 5 * math.sqrt(2.0 / n)
    stationary = samples[:, 15:] - m  # from t = 1.5 = 3 TC on
    lag = np.sum(stationary[:, 1:] * stationary[:, :-1]) / np.sum(stationary[:, :-1] ** 2)
    assert abs(lag - math.exp(-0.1 / tc)) <= 5 / math.sqrt(stationary.size)


@pytest.mark.parametrize("body, message", [
    ("INITIAL\nA = GAUSS(0.0, 1.0)\nDYNAMIC\nX = INTGRL(0.0, A)",
     "GAUSS cannot be used in INITIAL"),
    ("X = OU(0.0, 1.0, 1.0)", "TC of OU must be positive (got 0)"),
    ("X = GAUSS(S, 0.0, 1.0)\nY = INTGRL(0.0, X)\nS = Y", "SEED of GAUSS uses S"),
])
def test_random_arguments_are_checked(body, message):
    with pytest.raises(AmilError) as err:
        amilpy.loads(listing(body))
    assert message in err.value.render()


def test_a_seed_must_be_a_number():
    with pytest.raises(AmilError, match="seed must be a finite number"):
        amilpy.loads(GAUSS).run(seed=float("nan"))
