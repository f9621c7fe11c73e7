"""Robust statistics shared by the measurement modules: the median by one partition, the MAD standard
deviation, and an image's pixel noise (Immerkaer's Laplacian-difference mask).

The lowest of the measure package's modules (numpy and scipy.ndimage only): the clipping, zero-fill and edge
search modules all build on it.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi

__all__ = ["median", "robust_sigma", "estimate_noise"]


def robust_sigma(values, *, overwrite: bool = False) -> float:
    """Standard deviation estimated from the median absolute deviation (1.4826 MAD); ``overwrite``: a float
    array of the caller's own that may be reordered and overwritten (no copies).

    Examples
    --------
    >>> round(robust_sigma(np.random.default_rng(0).normal(0, 2, 100000)), 1)
    2.0
    """
    if overwrite and isinstance(values, np.ndarray) and values.dtype == np.float64 and values.ndim == 1:
        v = values
    else:
        v = np.asarray(values, dtype=float).ravel()
        overwrite = False
    if v.size == 0:
        return 0.0
    if overwrite:
        med = _median_inplace(v)
        np.abs(np.subtract(v, med, out=v), out=v)
        return float(1.482602218505602 * _median_inplace(v))
    dev = np.abs(v - median(v))
    return float(1.482602218505602 * _median_inplace(dev))


def median(values) -> float:
    """``np.median`` of the flattened ``values`` (the same value: the middle element, or the mean of the two
    middle ones; NaN where any is NaN), by one partition and without its overhead.

    Examples
    --------
    >>> median(np.array([3.0, 1.0, 2.0, 10.0]))
    2.5
    """
    v = np.asarray(values, dtype=float).ravel()
    return _median_inplace(v.copy())


def _median_inplace(v: np.ndarray) -> float:
    """:func:`median` of a 1-D float array that may be reordered."""
    n = v.size
    if n == 0:
        return float("nan")
    lo, hi = (n - 1) // 2, n // 2
    if n <= _SORT_MEDIAN:  # a short array: a sort costs less than a partition, and puts any NaN last
        v.sort()
        if np.isnan(v[-1]):
            return float("nan")
    elif np.isnan(v).any():
        return float("nan")
    else:
        v.partition([lo, hi] if lo != hi else lo)
    return float((v[lo] + v[hi]) / 2)


_SORT_MEDIAN = 256  # up to this many values the median sorts them (cheaper than np.partition's call)


def estimate_noise(image, *, band_rows: int = 512, valid=None) -> float:
    """Pixel noise standard deviation (image units) from Immerkaer's Laplacian-difference mask, robust (MAD).

    Plateaus and linear ramps give zero response; edges are a small fraction of the pixels and do not move the
    median.  Computed over bands of rows, so the memory stays O(band).  With ``valid`` (bool, the image's
    shape) only masks whose 3 x 3 pixels are all valid count.

    Examples
    --------
    >>> img = np.random.default_rng(1).normal(10.0, 0.5, (256, 256))
    >>> round(estimate_noise(img), 2)
    0.5
    """
    a = np.asarray(image)
    mask = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], dtype=np.float32)
    meds = []
    for y0 in range(0, max(a.shape[0] - 2, 1), band_rows):
        band = np.asarray(a[y0 : y0 + band_rows + 2], dtype=np.float32)
        if band.shape[0] < 3 or band.shape[1] < 3:
            continue
        r = ndi.correlate(band, mask, mode="nearest")[1:-1, 1:-1]
        if valid is not None:
            vb = np.asarray(valid[y0 : y0 + band_rows + 2])
            r = r[ndi.binary_erosion(vb, np.ones((3, 3), bool))[1:-1, 1:-1]]
            if r.size == 0:
                continue
        meds.append((np.median(np.abs(r)), r.size))
    if not meds:
        return 0.0
    m = np.array(meds)
    med = float(np.average(m[:, 0], weights=m[:, 1]))
    return 1.482602218505602 * med / 6.0  # ||mask||_2 = 6
