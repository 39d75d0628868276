"""Reference for Exercise 4 (seed 004): DC micromotor, elastic coupling, clutch, torque meter.

Equations (lab sheet 4.11-4.14 with the voltage balance; chain form 4.13):

    L*IA' = U - R*IA - KE*W1                            voltage balance
    J1*W1' = KT*IA - BV*W1 - MC1 - MFR                  rotor (4.11 with M1 = KT*i - losses)
    Jk*Wk' = MC(k-1) - MCk                              inner masses of the chain (4.13)
    Jn*Wn' = MC(n-1) - MOBC                             load (4.12, M2 = MOBC)
    THk'   = Wk - W(k+1);   MCk = ck*THk + bk*(Wk - W(k+1))

MFR is Coulomb friction with stiction: MF*sign(W1) while the rotor turns; at rest it
balances the net torque MNET = KT*IA - BV*W1 - MC1 as long as |MNET| <= MF. The clutch
variant multiplies the coupling and the load equation by SW = 0 before T1, 1 after, and
integrates the twist from T1 (zero initial twist).

The integration is hybrid: modes slip+ / slip- / stick, with events W1 = 0 (slip) and
MNET = +-MF (stick), each located by solve_ivp and followed by a restart; the clutch
instant T1 is a known breakpoint. Nothing here imports amilpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp
from scipy.integrate._ivp.ivp import OdeResult

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm

# FAULHABER 1331 T 012 SR catalogue data (DC-Micromotors 3.2 mNm series 1331 ... SR sheet).
U = 12.0  # V, nominal voltage
R = 13.7  # ohm, terminal resistance
L = 310e-6  # H, rotor inductance
KT = 11.4e-3  # N*m/A, torque constant
KE = 1.20e-3 / RPM  # V*s/rad, back-EMF constant 1.20 mV/rpm
J_ROTOR = 0.67e-7  # kg*m^2, rotor inertia 0.67 g*cm^2
MF = 0.12e-3  # N*m, friction torque
NO_LOAD_CURRENT = 0.0105  # A, catalogue no-load current (K_T*I0 = 0.1197 mN*m ~ MF)

# Exercise data (lab sheet 4.5).
J_OBC = 2.0 * J_ROTOR  # kg*m^2, load inertia = 2 x rotor inertia
M_OBC = 0.25 * KT * U / R  # N*m, load torque = 1/4 of the starting torque KT*U/R
C_COUPLING = 2.0  # N*m/rad, coupling stiffness
B_COUPLING = 6.0e-5  # N*m*s/rad, coupling damping (coupling-mode damping ratio ~ 0.1)

# Torque-meter stand (ex4_torque_meter.amil): motor - bellows coupling - torque-meter
# drive half | measuring shaft | torque-meter load half - bellows coupling - load.
# Assumed data of a 0.1 N*m in-line strain-gauge torque meter (see the listing header).
C_METER = 30.0  # N*m/rad, measuring-shaft torsional stiffness
J_METER_HALF = 0.5e-6  # kg*m^2, each half of the torque-meter rotor
B_METER = 3.0e-5 * C_METER  # N*m*s/rad, material damping, same b/c ratio as the coupling

STICK = 0  # mode code of a rotor held by static friction


def tau_m(j1: float = J_ROTOR) -> float:
    """Electromechanical time constant R*J/(KT*KE) of the unloaded motor [s]."""
    return R * j1 / (KT * KE)


def clutch_time() -> float:
    """T1 = 5 electromechanical time constants (lab sheet 4.5) [s]."""
    return 5.0 * tau_m()


def breakaway_time() -> float:
    """Instant at which KT*i(t) first reaches MF with the rotor held at rest [s].

    With W1 = 0 the voltage balance is a first-order lag: i = U/R*(1 - exp(-R*t/L)).
    """
    return -L / R * math.log(1.0 - R * MF / (KT * U))


def free_run_steady(bv: float = 0.0) -> tuple[float, float]:
    """Steady (speed [rad/s], current [A]) of the unloaded motor: KT*i = MF + BV*w."""
    w = (U - R * MF / KT) / (KE + R * bv / KT)
    return w, (MF + bv * w) / KT


def loaded_steady(bv: float = 0.0, c: float = C_COUPLING) -> dict[str, float]:
    """Steady state of the engaged drive: both masses at one speed, coupling carries MOBC."""
    w = (U - R * (MF + M_OBC) / KT) / (KE + R * bv / KT)
    return {"W": w, "IA": (MF + M_OBC + bv * w) / KT, "TH": M_OBC / c, "MC": M_OBC}


@dataclass(frozen=True)
class Chain:
    """Motor rotor followed by ``len(j) - 1`` elastic links and masses; load on the last."""

    j: tuple[float, ...]
    c: tuple[float, ...]
    b: tuple[float, ...]
    m_load: float = M_OBC
    bv: float = 0.0
    t_clutch: float | None = None  # two-mass chain only: coupling engaged at t_clutch

    @property
    def n(self) -> int:
        return len(self.j)

    def torques(self, y: NDArray[np.float64], sw: float) -> NDArray[np.float64]:
        """Coupling torques MC_k for the states ``y`` (columns allowed)."""
        n = self.n
        w = y[1 : 1 + n]
        th = y[1 + n :]
        c = np.asarray(self.c)[:, None] if y.ndim == 2 else np.asarray(self.c)
        b = np.asarray(self.b)[:, None] if y.ndim == 2 else np.asarray(self.b)
        return sw * (c * th + b * (w[:-1] - w[1:]))

    def net_torque(self, y: NDArray[np.float64], sw: float) -> NDArray[np.float64] | float:
        """Torque on the rotor other than Coulomb friction."""
        return KT * y[0] - self.bv * y[1] - self.torques(y, sw)[0]

    def rhs(self, y: NDArray[np.float64], mode: int, sw: float) -> NDArray[np.float64]:
        n = self.n
        mc = self.torques(y, sw)
        w = y[1 : 1 + n]
        dy = np.empty_like(y)
        dy[0] = (U - R * y[0] - KE * w[0]) / L
        mnet = KT * y[0] - self.bv * w[0] - mc[0]
        dy[1] = 0.0 if mode == STICK else (mnet - mode * MF) / self.j[0]
        for k in range(1, n - 1):
            dy[1 + k] = (mc[k - 1] - mc[k]) / self.j[k]
        dy[n] = sw * (mc[n - 2] - self.m_load) / self.j[n - 1]
        dy[1 + n :] = sw * (w[:-1] - w[1:])
        return dy


@dataclass
class Segment:
    t0: float
    t1: float
    mode: int
    sw: float
    sol: OdeResult


@dataclass
class Trajectory:
    chain: Chain
    segments: list[Segment] = field(default_factory=list)
    events: list[tuple[float, str]] = field(default_factory=list)

    def states(self, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """States (rows) and the clutch factor at the instants ``t``."""
        times = np.atleast_1d(np.asarray(t, dtype=float))
        n_state = 1 + 2 * self.chain.n - 1
        out = np.empty((n_state, times.size))
        sw = np.empty(times.size)
        starts = np.array([s.t0 for s in self.segments])
        idx = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, None)
        for k, seg in enumerate(self.segments):
            sel = idx == k
            if np.any(sel):
                out[:, sel] = seg.sol.sol(times[sel])
                sw[sel] = seg.sw
                if seg.mode == STICK:  # held exactly at rest, as the model says
                    out[1, sel] = 0.0
        return out, sw

    def sample(self, t: ArrayLike) -> dict[str, NDArray[np.float64]]:
        """Named variables (listing names) at the instants ``t``."""
        y, sw = self.states(t)
        n = self.chain.n
        res: dict[str, NDArray[np.float64]] = {"IA": y[0]}
        for k in range(n):
            res[f"W{k + 1}"] = y[1 + k]
        mc = self.chain.torques(y, 1.0) * sw
        for k in range(n - 1):
            res[f"TH{k + 1}"] = y[1 + n + k]
            res[f"MC{k + 1}"] = mc[k]
        res["MNET"] = KT * y[0] - self.chain.bv * y[1] - mc[0]
        return res

    def crossings(self) -> list[float]:
        """Instants at which the rotor speed W1 passes through zero while slipping."""
        return [t for t, what in self.events if what.startswith("W1=0")]


def simulate(chain: Chain, t_end: float, rtol: float = 1e-12, atol: float = 1e-18) -> Trajectory:
    """Integrate the hybrid drive from rest (all states zero) to ``t_end``.

    ``atol`` is tiny on purpose: the current (~1e-2 A), twists (~1e-3 rad) and speeds
    (~1e3 rad/s) differ by five decades, so the relative tolerance must govern.
    """
    n = chain.n
    y = np.zeros(1 + 2 * n - 1)
    t = 0.0
    traj = Trajectory(chain)
    mode = STICK  # at rest with no current: |MNET| = 0 <= MF
    while t < t_end:
        sw = 1.0 if chain.t_clutch is None or t >= chain.t_clutch else 0.0
        t_stop = t_end
        if chain.t_clutch is not None and t < chain.t_clutch:
            t_stop = min(t_end, chain.t_clutch)

        def f(
            _t: float, yy: NDArray[np.float64], m: int = mode, s: float = sw
        ) -> NDArray[np.float64]:
            return chain.rhs(yy, m, s)

        if mode == STICK:

            def up(_t: float, yy: NDArray[np.float64], s: float = sw) -> float:
                return float(chain.net_torque(yy, s)) - MF

            def down(_t: float, yy: NDArray[np.float64], s: float = sw) -> float:
                return float(chain.net_torque(yy, s)) + MF

            up.terminal, up.direction = True, 1.0  # type: ignore[attr-defined]
            down.terminal, down.direction = True, -1.0  # type: ignore[attr-defined]
            events = [up, down]
        else:

            def zero(_t: float, yy: NDArray[np.float64]) -> float:
                return float(yy[1])

            zero.terminal, zero.direction = True, -float(mode)  # type: ignore[attr-defined]
            events = [zero]
        sol = solve_ivp(
            f,
            (t, t_stop),
            y,
            method="DOP853",
            rtol=rtol,
            atol=atol,
            dense_output=True,
            events=events,
        )
        if sol.status < 0:
            raise RuntimeError(sol.message)
        traj.segments.append(Segment(t, float(sol.t[-1]), mode, sw, sol))
        t = float(sol.t[-1])
        y = sol.y[:, -1].copy()
        if sol.status == 1:  # a switching event ended the segment
            if mode == STICK:
                mode = 1 if sol.t_events[0].size else -1
                traj.events.append((t, f"breakaway {'+' if mode > 0 else '-'}"))
            else:
                y[1] = 0.0
                mnet = float(chain.net_torque(y, sw))
                mode = STICK if abs(mnet) <= MF else (1 if mnet > 0 else -1)
                traj.events.append((t, f"W1=0 -> {'stick' if mode == STICK else mode}"))
        elif chain.t_clutch is not None and math.isclose(t, chain.t_clutch) and t < t_end:
            traj.events.append((t, "clutch engaged"))
            if mode == STICK and abs(float(chain.net_torque(y, 1.0))) > MF:
                mode = 1 if float(chain.net_torque(y, 1.0)) > 0 else -1
    return traj


def elastic_chain(bv: float = 0.0) -> Chain:
    """ex4_elastic.amil: rotor + coupling + load, load connected from t = 0."""
    return Chain((J_ROTOR, J_OBC), (C_COUPLING,), (B_COUPLING,), bv=bv)


def clutch_chain() -> Chain:
    """ex4_clutch.amil: the same, coupling and load engaged at T1."""
    return Chain((J_ROTOR, J_OBC), (C_COUPLING,), (B_COUPLING,), t_clutch=clutch_time())


def meter_chain() -> Chain:
    """ex4_torque_meter.amil: rotor, coupling, meter half, shaft, meter half, coupling, load."""
    return Chain(
        (J_ROTOR, J_METER_HALF, J_METER_HALF, J_OBC),
        (C_COUPLING, C_METER, C_COUPLING),
        (B_COUPLING, B_METER, B_COUPLING),
    )


def engaged_matrix(chain: Chain) -> NDArray[np.float64]:
    """State matrix A of the engaged drive while the rotor slips (friction constant).

    States [IA, W1..Wn, TH1..TH(n-1)]; the constant terms (U, MF, MOBC) do not affect
    the eigenvalues, so A is assembled from the right-hand side by finite columns of a
    linear map (exact: the map is affine).
    """
    size = 1 + 2 * chain.n - 1
    base = chain.rhs(np.zeros(size), 1, 1.0)
    a = np.empty((size, size))
    for k in range(size):
        e = np.zeros(size)
        e[k] = 1.0
        a[:, k] = chain.rhs(e, 1, 1.0) - base
    return a


def coupling_mode(chain: Chain) -> tuple[float, float, complex]:
    """Damped frequency [rad/s], damping ratio and eigenvalue of the least-damped complex pair."""
    lam = np.linalg.eigvals(engaged_matrix(chain))
    pair = lam[lam.imag > 0]
    best = pair[np.argmax(pair.real)] if chain.n > 2 else pair[0]
    return float(best.imag), float(-best.real / abs(best)), complex(best)


if __name__ == "__main__":  # quick look when run by hand
    print(
        f"tau_m = {tau_m():.9g} s, T1 = {clutch_time():.9g} s, breakaway {breakaway_time():.6g} s"
    )
    print("free run", free_run_steady(), "loaded", loaded_steady())
    ch = clutch_chain()
    tr = simulate(ch, 0.5)
    print(tr.events)
    s = tr.sample([clutch_time(), 0.5])
    print({k: v.tolist() for k, v in s.items()})
    print("coupling mode", coupling_mode(ch), np.linalg.eigvals(engaged_matrix(ch)))
