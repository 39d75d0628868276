"""Draw the figures of docs/models.md from amilpy runs of the shipped models.

    python docs/make_model_figures.py            # all figures into docs/figures/
    python docs/make_model_figures.py --no-sweep # skip the hoist sweep (about a minute)
                                                 # and its comparison with `response`

The hoist sweep is done by hand, as in tests/test_models.py: each point is four runs of
the listing's 5 s, each started from the previous run's final state through the INCONs
X10, Y0, V10, V20, V30, PH0; the amplitude is half the peak-to-peak of Y over the last
3 s. The harmonic-balance curves come from tests/references/hoist.py.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import amilpy  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
OUT = ROOT / "docs" / "figures"
sys.path.insert(0, str(ROOT / "tests"))  # the references (pure SciPy) for the HB curves

from references import hoist  # noqa: E402


def _save(fig: plt.Figure, name: str) -> None:
    fig.tight_layout()
    fig.savefig(OUT / name, dpi=110)
    plt.close(fig)
    print("wrote", OUT / name)


def ex4_figures() -> None:
    r = amilpy.load(MODELS / "ex4_clutch.amil").run()[0]
    t1 = float(r["T1"][-1])
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, sel in ((ax1, slice(None)), (ax2, (r.t > t1 - 2e-4) & (r.t < t1 + 3e-3))):
        ax.plot(r.t[sel] * 1e3, r["W1"][sel], label="W1 rotor")
        ax.plot(r.t[sel] * 1e3, r["W2"][sel], label="W2 load")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_xlabel("t [ms]")
        ax.set_ylabel("rad/s")
    ax1.set_title("ex4_clutch: speeds, clutch at T1 = 35.13 ms")
    ax2.set_title("around T1: the rotor reverses twice")
    ax1.legend()
    _save(fig, "ex4_clutch_w.png")
    fig, ax = plt.subplots(figsize=(6, 3.6))
    sel = (r.t > t1 - 2e-4) & (r.t < t1 + 6e-3)
    ax.plot(r.t[sel] * 1e3, r["MC"][sel])
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("MC [N*m]")
    ax.set_title("ex4_clutch: coupling torque after engagement")
    _save(fig, "ex4_clutch_mc.png")
    r = amilpy.load(MODELS / "ex4_torque_meter.amil").run()[0]
    fig, ax = plt.subplots(figsize=(6, 3.6))
    sel = r.t < 0.05
    for name in ("MT", "M12", "M34"):
        ax.plot(r.t[sel] * 1e3, r[name][sel], label=name)
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("N*m")
    ax.set_title("ex4_torque_meter: reading MT and coupling torques")
    ax.legend()
    _save(fig, "ex4_torque_meter.png")


def hoist_time_figure() -> None:
    r = amilpy.load(MODELS / "hoist_backlash.amil").run()[0]
    fig, ax = plt.subplots(figsize=(8, 3.6))
    ax.plot(r.t, r["Y"], lw=0.8)
    for y in (-hoist.DELTA / 2, hoist.DELTA / 2):
        ax.axhline(y, color="r", lw=0.6, ls="--")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("Y [rad]")
    ax.set_title("hoist_backlash, W = 70 rad/s from rest: coupling twist (gap between dashes)")
    _save(fig, "hoist_y.png")


def hoist_sweep_figure() -> None:
    model = amilpy.load(MODELS / "hoist_backlash.amil")
    h = hoist.Hoist()
    state = {"X10": h.mn / h.c1, "Y0": h.half_gap + h.mn / h.c2}
    up = [round(x, 3) for x in np.arange(66.0, 75.01, 0.1)]
    down = up[::-1]
    amps: dict[str, list[float]] = {"up": [], "down": []}
    for key, ws in (("up", up), ("down", down)):
        for w in ws:
            for _ in range(4):
                r = model.run(W=w, rtol=1e-9, atol=1e-12, **state)[0]
                state = {
                    k: r.final[v]
                    for k, v in (
                        ("X10", "X1"),
                        ("Y0", "Y"),
                        ("V10", "V1"),
                        ("V20", "V2"),
                        ("V30", "V3"),
                        ("PH0", "PH"),
                    )
                }
            amps[key].append(0.5 * float(np.ptp(r["Y"][r.t >= 2.0])))
    np.savetxt(
        OUT / "hoist_sweep.csv",
        np.column_stack([up, amps["up"], down, amps["down"]]),
        delimiter=",",
        header="w_up,a_up,w_down,a_down",
        comments="",
    )
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(up, amps["up"], "o-", ms=3, color="tab:blue", label="amilpy, sweep up")
    ax.plot(down, amps["down"], "s-", ms=3, color="tab:red", label="amilpy, sweep down")
    a = np.linspace(1e-3, 0.06, 1500)
    w_hb, a_hb = hoist.harmonic_balance_curve(h, a, 60.0, 80.0)
    ax.plot(w_hb, a_hb, ".", ms=1.5, color="gray", label="harmonic balance, eq. (21)")
    ax.plot([hoist.skeleton(h, x) for x in a], a, "k--", lw=0.8, label="skeleton, eq. (16)")
    ax.set_xlim(66, 75)
    ax.set_ylim(0, 0.045)
    ax.set_xlabel("W [rad/s]")
    ax.set_ylabel("half peak-to-peak of Y [rad]")
    ax.set_title("hoist_backlash: amplitude-frequency characteristic (cf. paper Fig. 11)")
    ax.legend(fontsize=8)
    _save(fig, "hoist_sweep.png")


def hoist_response_figure() -> None:
    """The response curve (continuation) against the stepped sweep of `amilpy
    sweep` (20 s a point, the last 3 s measured, both ways, state carried) and the
    harmonic balance of eq. (21): drawn by amilpy's own `plot_response`."""
    from amilpy.output.analysis import plot_response

    model = amilpy.load(MODELS / "hoist_backlash.amil")
    h = hoist.Hoist()
    loaded = {"X10": h.mn / h.c1, "Y0": h.half_gap + h.mn / h.c2}
    resp = model.response("W", 67.5, 73.0, angle="PH=2*PI", measure="Y", settle=20.0,
                          **loaded)
    grid = [round(x, 3) for x in np.arange(67.5, 73.001, 0.1)]
    sweep = model.sweep("W", grid, both_ways=True, carry_state=True, settle=17.0,
                        measure="Y", fintim=20.0, **loaded)
    up, down = sweep.branch("up"), sweep.branch("down")
    # the undamped harmonic balance over the same window, sparse black dots under
    # the curve (its arms above 0.04 belong to no orbit the damped model reaches)
    w_hb, a_hb = hoist.harmonic_balance_curve(h, np.linspace(1e-3, 0.04, 120), 67.0, 73.5)
    plot_response(resp, str(OUT / "hoist_response_vs_sweep.png"), model, reference=[
        (w_hb, a_hb, "harmonic balance, eq. (21), undamped", "k."),
        (up[0], up[1], "amilpy sweep up, 20 s a point", "C2^"),
        (down[0], down[1], "amilpy sweep down", "C1v")])
    print("wrote", OUT / "hoist_response_vs_sweep.png")


def one_dof_figures() -> None:
    r = amilpy.load(MODELS / "crank_slider_startup.amil").run()[0]
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.plot(r["PHI"], r["W"])
    ax.set_xlabel("PHI [rad]")
    ax.set_ylabel("W [rad/s]")
    ax.set_title("crank_slider_startup: W(PHI) up to FINISH W = 10")
    _save(fig, "crank_slider_w_phi.png")
    r = amilpy.load(MODELS / "machine_unit.amil").run()[0]
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.plot(r.t, r["W"])
    ax.axhline(520 / 41, color="k", lw=0.6, ls="--")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("W [rad/s]")
    ax.set_title("machine_unit: start-up; dashed: (a - C0)/(b + k)")
    _save(fig, "machine_unit_w.png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-sweep", action="store_true")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    ex4_figures()
    hoist_time_figure()
    one_dof_figures()
    if not args.no_sweep:
        hoist_sweep_figure()
        hoist_response_figure()


if __name__ == "__main__":
    main()
