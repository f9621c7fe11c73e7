"""Zernike polynomials in Noll's order, normalised to unit rms over the unit disk (Noll 1976, JOSA 66, 207).

Part of :mod:`satchain.tf.optics`, which re-exports every public name: the wavefront of a
:class:`satchain.tf.pupil.PupilOTF` is given as Noll index -> rms coefficient in waves.

Examples
--------
>>> noll_to_nm(4), round(float(zernike_noll(4, 0.0, 0.0)), 6)  # defocus at the pupil centre: -sqrt(3)
((2, 0), -1.732051)
"""

from __future__ import annotations

import math

import numpy as np

from satchain._validate import as_float_array
from satchain.errors import ConfigError

__all__ = ["noll_to_nm", "zernike_noll"]


def noll_to_nm(j: int) -> tuple[int, int]:
    """Radial order ``n`` and signed azimuthal order ``m`` of Noll index ``j`` (Noll 1976, JOSA 66, 207).

    Even ``j`` carry ``cos(m theta)`` (m > 0), odd ``j`` ``sin`` (m < 0).

    Examples
    --------
    >>> [noll_to_nm(j) for j in (1, 2, 3, 4, 5, 6, 11)]
    [(0, 0), (1, 1), (1, -1), (2, 0), (2, -2), (2, 2), (4, 0)]
    """
    if isinstance(j, bool) or not isinstance(j, (int, np.integer)) or j < 1:
        raise ConfigError(f"Noll index j = {j!r}: must be an integer >= 1")
    j = int(j)
    n = (math.isqrt(8 * j - 7) - 1) // 2
    k = j - n * (n + 1) // 2 - 1  # position within the row
    am = 2 * ((k + 1) // 2) if n % 2 == 0 else 2 * (k // 2) + 1
    return n, (0 if am == 0 else (am if j % 2 == 0 else -am))


def zernike_noll(j: int, rho, theta):
    """Zernike polynomial ``Z_j(rho, theta)`` in Noll's order, normalised to unit rms over the unit disk.

    ``Z_j = sqrt(n + 1) R_n^0(rho)`` for m = 0 and ``sqrt(2 (n + 1)) R_n^|m|(rho) cos|sin(|m| theta)``
    otherwise (Noll 1976, JOSA 66, 207, eqs. 1-3), so ``(1/pi) int Z_i Z_j = delta_ij``. Noll 4 is defocus
    ``sqrt(3) (2 rho^2 - 1)``.

    Examples
    --------
    >>> round(float(zernike_noll(4, 1.0, 0.0)), 6)  # sqrt(3)
    1.732051
    """
    n, m = noll_to_nm(j)
    rho = as_float_array("rho", rho)
    theta = as_float_array("theta", theta)
    am = abs(m)
    radial = np.zeros(np.broadcast_shapes(rho.shape, theta.shape))
    for s in range((n - am) // 2 + 1):
        c = (-1) ** s * math.factorial(n - s)
        c /= math.factorial(s) * math.factorial((n + am) // 2 - s) * math.factorial((n - am) // 2 - s)
        radial = radial + c * rho ** (n - 2 * s)
    if m == 0:
        return math.sqrt(n + 1) * radial
    ang = np.cos(am * theta) if m > 0 else np.sin(am * theta)
    return math.sqrt(2 * (n + 1)) * radial * ang
