"""Reference for the crane hoist with backlash in the drum coupling (seed 002).

Three masses (motor I1, gear I2, drum I3), shaft c1 between 1 and 2, gear coupling with
circumferential backlash DELTA and stiffness c2 between 2 and 3. With the twists
X1 = psi1 - psi2 and Y = psi2 - psi3 (teeth in the middle of the gap at Y = 0):

    I1*V1' = MN - c1*X1 - d1*(V1 - V2)
    I2*V2' = c1*X1 + d1*(V1 - V2) - T2 + M0*sin(PH),   PH' = W
    I3*V3' = T2 - MN
    T2     = c2*dz(Y) + d2*Y'*[|Y| > DELTA/2],   dz = dead zone of half-width DELTA/2

Units: the paper's eq. (17) is reproduced only with inertias in kG*cm*s^2 and stiffnesses
and torques in kG*cm (checked by ``eq16_coefficients``); in SI each is x 0.0980665.

Closed forms here: the eigenproblem of the linear chain and the paper's eq. (17); the
harmonic linearisation of the dead zone (eqs. 11-14) with the mean-torque condition; the
skeleton curve (eq. 16 with q(a)); the harmonic-balance amplitude curve (eq. 21) and its
folds. ``simulate`` integrates the equations with the contact edges |Y| = DELTA/2 located
as events; ``sweep`` steps W carrying the state, as ``amilpy sweep --carry-state`` does.
Nothing here imports amilpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

KGCM = 0.0980665  # N*m per kG*cm (also kg*m^2 per kG*cm*s^2)

# Paper's data, section 3.2 and 3.3, read in kG*cm units.
I1_KG, I2_KG, I3_KG = 25.6, 15.0, 19.1  # kG*cm*s^2
C1_KG, C2_KG = 74e4, 7.1e4  # kG*cm/rad
MN_KG, M0_KG = 1420.0, 77.0  # kG*cm
DELTA = 0.0087  # rad, circumferential backlash


@dataclass(frozen=True)
class Hoist:
    i1: float = I1_KG * KGCM
    i2: float = I2_KG * KGCM
    i3: float = I3_KG * KGCM
    c1: float = C1_KG * KGCM
    c2: float = C2_KG * KGCM
    delta: float = DELTA
    mn: float = MN_KG * KGCM
    m0: float = M0_KG * KGCM
    zeta: float = 0.005

    @property
    def half_gap(self) -> float:
        return 0.5 * self.delta

    @property
    def beta(self) -> float:
        """Stiffness-proportional damping factor giving the linear coupling mode ratio zeta."""
        return 2.0 * self.zeta / linear_frequencies(self, self.c2)[0]


def eq16_coefficients(h: Hoist, q: float) -> tuple[float, float, float]:
    """Coefficients (A, B, C) of A*lam^4 - B*lam^2 + C = 0 (eq. 16 without the zero root)."""
    a = h.i1 * h.i2 * h.i3
    b = h.i1 * q * (h.i2 + h.i3) + h.i3 * h.c1 * (h.i1 + h.i2)
    c = (h.i1 + h.i2 + h.i3) * h.c1 * q
    return a, b, c


def linear_frequencies(h: Hoist, q: float) -> tuple[float, float]:
    """Nonzero natural frequencies (lam2, lam3) [rad/s] for coupling stiffness q."""
    a, b, c = eq16_coefficients(h, q)
    disc = math.sqrt(b * b - 4.0 * a * c)
    return math.sqrt((b - disc) / (2 * a)), math.sqrt((b + disc) / (2 * a))


def eigen_frequencies(h: Hoist, q: float) -> NDArray[np.float64]:
    """All three natural frequencies from the generalised eigenproblem K v = lam^2 M v."""
    k = np.array([[h.c1, -h.c1, 0.0], [-h.c1, h.c1 + q, -q], [0.0, -q, q]])
    m = np.diag([h.i1, h.i2, h.i3])
    lam2 = np.sort(np.linalg.eigvals(np.linalg.solve(m, k)).real)
    return np.sqrt(np.clip(lam2, 0.0, None))


def eq17(q_over_c2: float) -> tuple[float, float]:
    """The paper's eq. (17) with its rounded coefficients: (lam2, lam3) [rad/s]."""
    s = 4.25 * q_over_c2 + 39.0
    root = math.sqrt(s * s * 1e6 - 430.0 * q_over_c2 * 1e6)
    return math.sqrt(s * 1e3 - root), math.sqrt(s * 1e3 + root)


# --- harmonic linearisation of the dead zone (eqs. 11-14) --------------------------------


def _ramp_harmonics(a0: float, a: float, e: float) -> tuple[float, float]:
    """Mean and first sine coefficient of max(a0 + a*sin(psi) - e, 0) over one period."""
    s = (e - a0) / a
    if s >= 1.0:
        return 0.0, 0.0
    if s <= -1.0:
        return a0 - e, a
    alpha = math.asin(s)
    ca = math.cos(alpha)
    mean = a / (2 * math.pi) * (2 * ca - s * (math.pi - 2 * alpha))
    first = a / math.pi * ((math.pi - 2 * alpha) / 2 - s * ca)
    return mean, first


def dead_zone_harmonics(h: Hoist, a0: float, a: float) -> tuple[float, float]:
    """(f0, q): mean torque (eq. 11) and equivalent stiffness (eq. 12) of c2*dz(a0 + a sin)."""
    e = h.half_gap
    m_pos, b_pos = _ramp_harmonics(a0, a, e)
    # min(y + e, 0) = -max(-y - e, 0) and -y = -a0 + a*sin(psi + pi): its first sine
    # coefficient changes sign twice, so it adds with the same sign as the positive side.
    m_neg, b_neg = _ramp_harmonics(-a0, a, e)
    return h.c2 * (m_pos - m_neg), h.c2 * (b_pos + b_neg) / a


def mean_offset(h: Hoist, a: float) -> float:
    """a0 such that the mean coupling torque equals MN (eq. 14: f0 of F(x) = F(y) - MN = 0)."""
    hi = h.half_gap + h.mn / h.c2 + a + 1.0
    return brentq(
        lambda a0: dead_zone_harmonics(h, a0, a)[0] - h.mn, -hi, hi, xtol=1e-15, rtol=1e-15
    )


def q_of_a(h: Hoist, a: float) -> float:
    """Equivalent coupling stiffness q(a0(a), a) along the mean-torque condition."""
    return dead_zone_harmonics(h, mean_offset(h, a), a)[1]


def skeleton(h: Hoist, a: float) -> float:
    """Backbone (skeleton) frequency lam2 for amplitude a: eq. (16) with q = q(a)."""
    return linear_frequencies(h, q_of_a(h, a))[0]


def eq21_amplitude(h: Hoist, q: float, w: float) -> float:
    """|a| from eq. (21): coupling-twist amplitude of the linearised, undamped system."""
    d3 = q - h.i3 * w * w
    ieff = h.i2 + h.i3 * q / d3 + h.i1 * h.c1 / (h.c1 - h.i1 * w * w)
    return abs(h.m0 * h.i3 / (d3 * ieff))


def eq21_frequencies(h: Hoist, a: float) -> list[float]:
    """All forcing frequencies w > 0 at which eq. (21) gives amplitude a (q = q(a)).

    Multiplying eq. (21) out gives a quadratic in w^2 for each sign of the right side:
    a*P(w^2) = +-M0*I3*(c1 - I1*w^2), P = [I2*(q - I3*W) + I3*q]*(c1 - I1*W) + I1*c1*(q - I3*W).
    """
    q = q_of_a(h, a)
    i1, i2, i3, c1 = h.i1, h.i2, h.i3, h.c1
    # P(W) = p2*W^2 + p1*W + p0
    p2 = i2 * i3 * i1
    p1 = -(i2 * q + i3 * q) * i1 - i2 * i3 * c1 - i1 * c1 * i3
    p0 = (i2 * q + i3 * q) * c1 + i1 * c1 * q
    roots: list[float] = []
    for sign in (1.0, -1.0):
        r = np.roots([a * p2, a * p1 + sign * h.m0 * i3 * i1, a * p0 - sign * h.m0 * i3 * c1])
        roots += [math.sqrt(x.real) for x in r if abs(x.imag) < 1e-9 * abs(x) and x.real > 0]
    return sorted(roots)


def harmonic_balance_curve(
    h: Hoist, amplitudes: NDArray[np.float64], w_lo: float = 40.0, w_hi: float = 110.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points (w, a) of eq. (21) with q(a) in the band w_lo..w_hi around the lam2 resonance."""
    ws: list[float] = []
    amps: list[float] = []
    for a in amplitudes:
        for w in eq21_frequencies(h, float(a)):
            if w_lo <= w <= w_hi:
                ws.append(w)
                amps.append(float(a))
    return np.array(ws), np.array(amps)


def _branches(h: Hoist, a: float, w_lo: float, w_hi: float) -> tuple[float, float]:
    """The two eq. (21) frequencies below and above the backbone (nan if absent)."""
    lam = skeleton(h, a)
    ws = [w for w in eq21_frequencies(h, a) if w_lo <= w <= w_hi]
    below = max((w for w in ws if w < lam), default=math.nan)
    above = min((w for w in ws if w > lam), default=math.nan)
    return below, above


def folds(h: Hoist, a_max: float = 0.2, n: int = 4000) -> dict[str, float]:
    """Turning points of the harmonic-balance curve around the lam2 resonance.

    The curve leans to low frequencies (softening while the teeth separate), so:
      * w_up   - the small-amplitude branch below the backbone ends here (largest w
                 on it); an up-sweep jumps up near w_up;
      * w_down - the large-amplitude branch above the backbone turns back here
                 (smallest w on it past the peak); a down-sweep jumps down near w_down.
    Also returned: a_sep, the amplitude at which the teeth first separate (MN/c2).
    """
    a_sep = h.mn / h.c2
    amps = np.linspace(a_sep * 0.2, a_max, n)
    below = np.array([_branches(h, float(a), 30.0, 120.0)[0] for a in amps])
    above = np.array([_branches(h, float(a), 30.0, 120.0)[1] for a in amps])
    # The below-backbone branch rises with a to a maximum, then falls: that maximum is w_up.
    k_up = int(np.nanargmax(below))
    w_up = _refine(h, amps, k_up, lambda a: _branches(h, a, 30.0, 120.0)[0], maximise=True)
    # The above-backbone branch falls with a to a minimum (then rises: hardening).
    k_dn = int(np.nanargmin(above))
    w_dn = _refine(h, amps, k_dn, lambda a: _branches(h, a, 30.0, 120.0)[1], maximise=False)
    return {
        "w_up": w_up[0],
        "a_up": w_up[1],
        "w_down": w_dn[0],
        "a_down": w_dn[1],
        "a_sep": a_sep,
        "lam2_linear": linear_frequencies(h, h.c2)[0],
    }


def _refine(
    h: Hoist, amps: NDArray[np.float64], k: int, f: object, maximise: bool
) -> tuple[float, float]:
    """Golden-section refinement of an extremum of f(a) bracketed by amps[k-1..k+1]."""
    from scipy.optimize import minimize_scalar

    fn = f  # type: ignore[assignment]
    lo = float(amps[max(k - 1, 0)])
    hi = float(amps[min(k + 1, amps.size - 1)])
    sgn = -1.0 if maximise else 1.0
    res = minimize_scalar(
        lambda a: sgn * fn(a), bounds=(lo, hi), method="bounded", options={"xatol": 1e-12}
    )  # type: ignore[operator]
    return float(sgn * res.fun), float(res.x)


def _gated_damping(h: Hoist, a0: float, a: float) -> float:
    """Equivalent viscous coefficient r (eq. 10: alpha_1/a) of d2*Y'*[|Y| > DELTA/2].

    For Y = a0 + a*sin(psi), Y' = a*w*cos(psi): r = d2/pi * integral over contact of cos^2.
    """
    e = h.half_gap
    total = 0.0
    for s in ((e - a0) / a, (e + a0) / a):  # upper contact sin(psi) > s; lower likewise
        if s <= -1.0:
            total += math.pi  # in contact the whole period on this side (counted once below)
        elif s < 1.0:
            al = math.asin(s)
            total += (math.pi - 2 * al) / 2 - math.sin(2 * al) / 2
    return h.beta * h.c2 / math.pi * min(total, math.pi)


def damped_hb_folds(
    h: Hoist,
    w_lo: float = 64.0,
    w_hi: float = 76.0,
    dw: float = 0.005,
    a_max: float = 0.08,
    na: int = 6000,
) -> dict[str, float]:
    """Folds of the harmonic-balance curve with the listing's damping included.

    Eq. (21) with complex stiffnesses c1 + i*w*d1 and q + i*w*r(a) (r from
    ``_gated_damping``); for each w the amplitudes a solving a = G(a, w) are counted on a
    fine grid; the band where three solutions coexist is [w_down, w_up].
    """
    amps = np.linspace(1e-4, a_max, na)
    a0s = np.array([mean_offset(h, float(a)) for a in amps])
    qs = np.array(
        [dead_zone_harmonics(h, float(x0), float(a))[1] for x0, a in zip(a0s, amps, strict=True)]
    )
    rs = np.array([_gated_damping(h, float(x0), float(a)) for x0, a in zip(a0s, amps, strict=True)])
    d1 = h.beta * h.c1
    multi: list[float] = []
    for w in np.arange(w_lo, w_hi + 0.5 * dw, dw):
        k1 = h.c1 + 1j * w * d1
        k2 = qs + 1j * w * rs
        ieff = h.i2 + h.i1 * k1 / (k1 - h.i1 * w * w) + h.i3 * k2 / (k2 - h.i3 * w * w)
        g = np.abs(h.m0 * h.i3 / ((k2 - h.i3 * w * w) * ieff))
        f = amps - g
        if np.count_nonzero(np.sign(f[1:]) != np.sign(f[:-1])) >= 3:
            multi.append(float(w))
    if not multi:
        return {"w_down": math.nan, "w_up": math.nan}
    return {"w_down": min(multi), "w_up": max(multi)}


# --- time response -------------------------------------------------------------------------

GAP, PLUS, MINUS = 0, 1, -1


def _contact(h: Hoist, y: float) -> int:
    e = h.half_gap
    return PLUS if y > e else (MINUS if y < -e else GAP)


def rhs(h: Hoist, w: float, mode: int, st: NDArray[np.float64]) -> NDArray[np.float64]:
    """States [X1, Y, V1, V2, V3, PH]."""
    x1, y, v1, v2, v3, ph = st
    beta = h.beta
    d1, d2 = beta * h.c1, beta * h.c2
    e = h.half_gap
    yd = v2 - v3
    t2 = 0.0 if mode == GAP else h.c2 * (y - mode * e) + d2 * yd
    m1 = h.c1 * x1 + d1 * (v1 - v2)
    return np.array(
        [
            v1 - v2,
            yd,
            (h.mn - m1) / h.i1,
            (m1 - t2 + h.m0 * math.sin(ph)) / h.i2,
            (t2 - h.mn) / h.i3,
            w,
        ]
    )


@dataclass
class Response:
    t: NDArray[np.float64]
    y: NDArray[np.float64]  # states on t, rows [X1, Y, V1, V2, V3, PH]
    edges: list[float]  # instants at which |Y| crossed DELTA/2
    final: NDArray[np.float64]

    def torque(self, h: Hoist) -> NDArray[np.float64]:
        """Coupling torque T2 on the output grid."""
        e = h.half_gap
        y = self.y[1]
        yd = self.y[3] - self.y[4]
        d2 = h.beta * h.c2
        dz = np.where(y > e, y - e, np.where(y < -e, y + e, 0.0))
        return h.c2 * dz + d2 * yd * (np.abs(y) > e)


def simulate(
    h: Hoist,
    w: float,
    t_span: tuple[float, float],
    y0: NDArray[np.float64] | None = None,
    t_eval: NDArray[np.float64] | None = None,
    rtol: float = 1e-12,
    atol: float = 1e-14,
) -> Response:
    """Integrate with each contact edge located by an event and a restart in the new mode."""
    st = np.zeros(6) if y0 is None else np.array(y0, dtype=float)
    t0, t1 = t_span
    e = h.half_gap
    starts: list[float] = []
    dense: list[object] = []
    edges: list[float] = []
    mode = _contact(h, float(st[1]))
    t = t0
    while t < t1:

        def f(_t: float, s: NDArray[np.float64], m: int = mode) -> NDArray[np.float64]:
            return rhs(h, w, m, s)

        if mode == GAP:

            def up(_t: float, s: NDArray[np.float64]) -> float:
                return float(s[1] - e)

            def down(_t: float, s: NDArray[np.float64]) -> float:
                return float(s[1] + e)

            up.terminal, up.direction = True, 1.0  # type: ignore[attr-defined]
            down.terminal, down.direction = True, -1.0  # type: ignore[attr-defined]
            events = [up, down]
        else:

            def leave(_t: float, s: NDArray[np.float64], m: int = mode) -> float:
                return float(s[1] - m * e)

            leave.terminal, leave.direction = True, -float(mode)  # type: ignore[attr-defined]
            events = [leave]
        sol = solve_ivp(
            f,
            (t, t1),
            st,
            method="DOP853",
            rtol=rtol,
            atol=atol,
            dense_output=t_eval is not None,
            events=events,
        )
        if sol.status < 0:
            raise RuntimeError(sol.message)
        starts.append(t)
        dense.append(sol.sol)
        t = float(sol.t[-1])
        st = sol.y[:, -1].copy()
        if sol.status == 1:  # a contact edge: restart in the new mode
            edges.append(t)
            if mode == GAP:
                mode = PLUS if st[1] > 0 else MINUS
            else:
                mode = GAP
            st[1] = (mode if mode != GAP else _sign(st[1])) * e
    if t_eval is None:
        return Response(np.array([t1]), st[:, None], edges, st)
    tt = np.asarray(t_eval, dtype=float)
    idx = np.clip(np.searchsorted(np.array(starts), tt, side="right") - 1, 0, None)
    yy = np.empty((6, tt.size))
    for k, sol_k in enumerate(dense):
        sel = idx == k
        if np.any(sel):
            yy[:, sel] = sol_k(tt[sel])  # type: ignore[operator]
    return Response(tt, yy, edges, st)


def _sign(x: float) -> int:
    return 1 if x >= 0 else -1


def sweep(
    h: Hoist,
    ws: list[float],
    settle: float,
    measure: float,
    y0: NDArray[np.float64] | None = None,
    dt_sample: float = 1e-3,
    rtol: float = 1e-10,
) -> tuple[list[float], NDArray[np.float64]]:
    """Step the forcing frequency, carrying the state; half peak-to-peak of Y after settle.

    The phase PH is a state, so the forcing stays continuous when W changes. Y is sampled
    every ``dt_sample`` from the start of the measuring window (the listing's OUTDEL grid:
    the sampled peak of a 70 rad/s oscillation on a 1 ms grid is low by up to 6e-4 of the
    amplitude, so a comparison must sample alike). Returns the amplitudes and final state.
    """
    st = np.zeros(6) if y0 is None else y0
    amps: list[float] = []
    t = 0.0
    for w in ws:
        r1 = simulate(h, w, (t, t + settle), st, rtol=rtol, atol=1e-13)
        n = int(round(measure / dt_sample))
        grid = t + settle + dt_sample * np.arange(n + 1)
        r2 = simulate(h, w, (t + settle, grid[-1]), r1.final, t_eval=grid, rtol=rtol, atol=1e-13)
        amps.append(0.5 * float(r2.y[1].max() - r2.y[1].min()))
        st = r2.final
        t = float(grid[-1])
    return amps, st


def with_zeta(zeta: float) -> Hoist:
    return replace(Hoist(), zeta=zeta)


if __name__ == "__main__":
    h = Hoist()
    print(
        "lam (q=c2) eig",
        eigen_frequencies(h, h.c2),
        "eq16",
        linear_frequencies(h, h.c2),
        "eq17",
        eq17(1.0),
    )
    print("beta", h.beta, "a_sep", h.mn / h.c2)
    for a in (0.01, 0.02, 0.025, 0.03, 0.04, 0.06, 0.1, 0.2):
        print(a, mean_offset(h, a), q_of_a(h, a) / h.c2, skeleton(h, a))
    print(folds(h))
    print("damped", damped_hb_folds(h))
