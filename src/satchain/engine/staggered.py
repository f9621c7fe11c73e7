"""Staggered arrays combined onto the half-pitch grid (SPOT-5's supermode; the model: :mod:`satchain.tf.staggered`).

Array A samples the focal-plane image (already through the optics and the ``p``-wide pixel aperture) at
``(i p, j p)``, array B at ``((i + 1/2) p, (j + 1/2) p)``. :func:`staggered_samples` takes both from an image
formed on the ``p / 2`` grid (A: the even rows and columns, B: the odd ones); :func:`combine_staggered` puts them
back on the ``p / 2`` grid (A at even-even, B at odd-odd) and fills each other point with the mean of its lattice
neighbours (up, down, left, right: the ``quincunx_bilinear`` combination, transfer function
:func:`satchain.tf.staggered.combination_otf`); at the border, of those that exist.
"""

from __future__ import annotations

import numpy as np

__all__ = ["combine_staggered", "staggered_samples"]


def staggered_samples(image_half_pitch) -> tuple[np.ndarray, np.ndarray]:
    """The two arrays' samples ``(A, B)`` from an image on the ``p / 2`` grid: ``A = image[0::2, 0::2]``,
    ``B = image[1::2, 1::2]`` (B cropped to A's shape when the image has an odd size).

    Examples
    --------
    >>> a, b = staggered_samples(np.arange(16.0).reshape(4, 4))
    >>> a.tolist(), b.tolist()
    ([[0.0, 2.0], [8.0, 10.0]], [[5.0, 7.0], [13.0, 15.0]])
    """
    img = np.asarray(image_half_pitch)
    if img.ndim != 2 or min(img.shape) < 2:
        raise ValueError(f"image_half_pitch: shape {img.shape}: must be a 2-D image of at least 2 x 2")
    ny, nx = img.shape[0] // 2, img.shape[1] // 2
    return img[0 : 2 * ny : 2, 0 : 2 * nx : 2].copy(), img[1 : 2 * ny : 2, 1 : 2 * nx : 2].copy()


def combine_staggered(a, b, *, method: str = "quincunx_bilinear") -> np.ndarray:
    """The two arrays combined on the ``p / 2`` grid (shape ``2 x`` theirs, float64): A at even rows and columns,
    B at odd ones, every other point the mean of its up, down, left and right neighbours (those inside).

    Examples
    --------
    >>> combine_staggered(np.full((2, 2), 3.0), np.full((2, 2), 3.0)).tolist()[0]
    [3.0, 3.0, 3.0, 3.0]
    """
    from satchain.tf.staggered import COMBINATIONS

    if method not in COMBINATIONS:
        raise ValueError(f"method = {method!r}: must be one of {', '.join(COMBINATIONS)}")
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.ndim != 2 or a.shape != b.shape:
        raise ValueError(f"a, b: shapes {a.shape} and {b.shape}: must be the same 2-D shape")
    ny, nx = a.shape
    out = np.zeros((2 * ny, 2 * nx))
    known = np.zeros(out.shape, bool)
    out[0::2, 0::2], out[1::2, 1::2] = a, b
    known[0::2, 0::2] = known[1::2, 1::2] = True
    total = np.zeros(out.shape)
    count = np.zeros(out.shape)
    for dy, dx in ((1, 0), (-1, 0), (0, 1), (0, -1)):  # the four lattice neighbours at p / 2
        src = (slice(max(dy, 0), out.shape[0] + min(dy, 0)), slice(max(dx, 0), out.shape[1] + min(dx, 0)))
        dst = (slice(max(-dy, 0), out.shape[0] + min(-dy, 0)), slice(max(-dx, 0), out.shape[1] + min(-dx, 0)))
        total[dst] += np.where(known[src], out[src], 0.0)
        count[dst] += known[src]
    fill = ~known
    out[fill] = total[fill] / count[fill]
    return out
