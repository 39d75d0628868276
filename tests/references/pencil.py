"""Matrix-pencil fit: exponents of a uniformly sampled sum of complex exponentials.

Used to "fit" a simulated signal (e.g. the coupling torque MC(t) of Exercise 4) and
recover the eigenvalues of the linear system that produced it. Between two switching
instants the drive is linear with constant forcing, so the signal is exactly
``c0 + sum_i c_i exp(lambda_i t)``; the pencil recovers the lambda_i without an initial
guess, to roughly the accuracy of the samples (Hua & Sarkar, IEEE Trans. ASSP 38, 1990).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def matrix_pencil(y: ArrayLike, dt: float, n_modes: int) -> NDArray[np.complex128]:
    """Return the ``n_modes`` continuous-time exponents present in samples ``y``.

    ``y`` must be sampled on a uniform grid of step ``dt``. A constant offset counts
    as one mode (exponent 0).
    """
    samples = np.asarray(y, dtype=float)
    n = samples.size
    pencil = n // 2  # the pencil parameter N/2 minimises the noise sensitivity
    hankel = np.array([samples[i : i + pencil + 1] for i in range(n - pencil)])
    _, _, vh = np.linalg.svd(hankel, full_matrices=False)
    v = vh[:n_modes].conj().T
    v1, v2 = v[:-1], v[1:]
    z = np.linalg.eigvals(np.linalg.pinv(v1) @ v2)
    return np.log(z.astype(complex)) / dt
