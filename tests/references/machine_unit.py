"""Reference for the machine unit in steady motion (seed 003, data of issue 3).

    I(phi)*w' + 0.5*I'(phi)*w^2 = (a - b*w) - (C0 + C1*sin(phi) + k*w),   phi' = w
    I = I0 + I1*sin^2(phi)

In steady motion w(phi) is 2*pi-periodic; the kinetic energy repeats each revolution, so
the work of the torques over one revolution vanishes:

    2*pi*(a - C0) - (b + k) * integral_0^{2 pi} w dphi = 0
    => revolution mean of w (mean over phi) = (a - C0)/(b + k).

``simulate`` integrates at rtol 1e-12 with the instants phi = 2*pi*n located as events, and
measures per revolution: the period T, the time mean 2*pi/T and the phi mean
(integral of w dphi)/(2*pi). Nothing here imports amilpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

I0, I1 = 8.0, 3.0  # kg*m^2
A, B = 600.0, 40.0  # N*m, N*m*s/rad
C0, C1, K = 80.0, 20.0, 1.0  # N*m, N*m, N*m*s/rad

PHI_MEAN_SPEED = (A - C0) / (B + K)  # exact, from the energy balance


def rhs(_t: float, s: np.ndarray) -> list[float]:
    phi, w, _aw = s
    i = I0 + I1 * math.sin(phi) ** 2
    di = I1 * math.sin(2.0 * phi)
    torque = (A - B * w) - (C0 + C1 * math.sin(phi) + K * w)
    return [w, (torque - 0.5 * di * w * w) / i, w * w]


@dataclass
class Revolution:
    t0: float
    t1: float
    w_min: float
    w_max: float
    phi_mean: float  # (integral of w dphi)/(2 pi)

    @property
    def time_mean(self) -> float:
        return 2.0 * math.pi / (self.t1 - self.t0)

    @property
    def nonuniformity(self) -> float:
        """Coefficient of fluctuation (w_max - w_min)/w_mean."""
        return (self.w_max - self.w_min) / self.time_mean


def simulate(t_end: float = 10.0) -> tuple[list[Revolution], object]:
    def rev(_t: float, s: np.ndarray) -> float:
        return math.sin(0.5 * s[0])  # zero at phi = 2*pi*n

    sol = solve_ivp(
        rhs,
        (0.0, t_end),
        [0.0, 0.0, 0.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-14,
        events=[rev],
        dense_output=True,
    )
    times = [0.0] + [t for t in sol.t_events[0] if t > 0]
    revs: list[Revolution] = []
    for t0, t1 in zip(times[:-1], times[1:], strict=True):
        tt = np.linspace(t0, t1, 2001)
        y = sol.sol(tt)
        revs.append(
            Revolution(
                t0,
                t1,
                float(y[1].min()),
                float(y[1].max()),
                float((y[2][-1] - y[2][0]) / (2 * math.pi)),
            )
        )
    return revs, sol


if __name__ == "__main__":
    revs, _ = simulate()
    for r in revs[-3:]:
        print(r, r.time_mean, r.nonuniformity)
    print("energy balance", PHI_MEAN_SPEED)
