"""Border reads by slices (BorderedWindow, take) against the index-map definition of each border rule, and the
fast paths' refusals of non-finite input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain import load_preset
from satchain.engine.simulate import simulate
from satchain.engine.sources import ArraySource, BorderedWindow, read_with_border, take
from satchain.engine.spectral import _fold, sampling_matrix
from satchain.engine.tiling import Window, footprint_weights
from satchain.errors import InputError


def _index_map(start: int, length: int, n: int, rule: str) -> np.ndarray:
    """Source index of every window position (-1: outside, for "constant"), written out independently."""
    out = []
    for i in range(start, start + length):
        if rule == "periodic":
            out.append(i % n)
        elif rule == "symmetric":  # ... 1 0 | 0 1 ... n-1 | n-1 n-2 ...
            j = i % (2 * n)
            out.append(j if j < n else 2 * n - 1 - j)
        else:
            out.append(i if 0 <= i < n else -1)
    return np.array(out)


@settings(max_examples=60, deadline=None)
@given(
    ny=st.integers(1, 9),
    nx=st.integers(1, 9),
    r0=st.integers(-25, 25),
    c0=st.integers(-25, 25),
    h=st.integers(1, 30),
    w=st.integers(1, 30),
    rule=st.sampled_from(["symmetric", "periodic", "constant"]),
    cut=st.tuples(st.integers(0, 30), st.integers(0, 30)),
)
def test_bordered_window_rows_equal_the_index_map(ny, nx, r0, c0, h, w, rule, cut):
    a = np.arange(ny * nx, dtype=np.float64).reshape(ny, nx) / 7.0
    iy, ix = _index_map(r0, h, ny, rule), _index_map(c0, w, nx, rule)
    want = np.where((iy[:, None] >= 0) & (ix[None, :] >= 0), a[np.maximum(iy, 0)][:, np.maximum(ix, 0)], 0.25)
    bw = BorderedWindow(ArraySource(a, pixel_m=1.0), Window(r0, c0, h, w), rule=rule, value=0.25, dtype=np.float32)
    np.testing.assert_array_equal(np.asarray(bw), want.astype(np.float32))
    lo, hi = min(cut), max(cut)
    np.testing.assert_array_equal(bw[lo:hi], want[lo:hi].astype(np.float32))  # any chunk of rows
    got = read_with_border(ArraySource(a, pixel_m=1.0), Window(r0, c0, h, w), rule=rule, value=0.25)
    np.testing.assert_array_equal(got, want)


@settings(max_examples=40, deadline=None)
@given(
    iy=st.lists(st.integers(0, 11), min_size=1, max_size=25),
    ix=st.lists(st.integers(0, 7), min_size=1, max_size=25),
)
def test_take_equals_fancy_indexing(iy, ix):
    a = np.arange(12 * 8, dtype=np.float32).reshape(12, 8)
    np.testing.assert_array_equal(take(a, np.array(iy), np.array(ix)), a[np.ix_(iy, ix)])


def test_a_window_inside_a_float32_array_is_not_copied():
    a = np.ones((50, 40), dtype=np.float32)
    block = read_with_border(ArraySource(a, pixel_m=1.0), Window(5, 6, 20, 10), rule="symmetric", dtype=np.float32)
    assert np.shares_memory(block, a)


def test_fold_sums_each_residue():
    rng = np.random.default_rng(4)
    m = np.concatenate([np.arange(12), np.arange(-11, 0)])  # a DFT band's order
    v = rng.normal(size=(m.size, 3)) + 1j * rng.normal(size=(m.size, 3))
    for n in (1, 5, 8, 23, 40):
        want = np.array([v[np.mod(m, n) == r].sum(axis=0) for r in range(n)])
        np.testing.assert_allclose(_fold(v, m, n, axis=0), want, atol=1e-12)
        np.testing.assert_allclose(_fold(v.T, m, n, axis=1), want.T, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    lo=st.integers(-60, 10),
    size=st.integers(1, 90),
    n=st.integers(1, 50),
    cuts=st.integers(0, 4),
    seed=st.integers(0, 10**6),
)
def test_fold_of_runs_in_any_order_sums_each_residue_in_increasing_m(lo, size, n, cuts, seed):
    """Consecutive frequencies split into runs given in any order: each residue's sum, exactly as summing
    its terms in increasing ``m`` (the order of the former sorted, period-by-period fold)."""
    rng = np.random.default_rng(seed)
    full = np.arange(lo, lo + size)
    pieces = np.split(full, np.sort(rng.choice(np.arange(1, size), min(cuts, size - 1), replace=False)))
    m = np.concatenate([pieces[i] for i in rng.permutation(len(pieces))])
    v = rng.normal(size=(m.size, 2)) + 1j * rng.normal(size=(m.size, 2))
    want = np.zeros((n, 2), dtype=complex)
    for j in np.argsort(m):  # increasing m
        want[np.mod(m[j], n)] += v[j]
    assert np.array_equal(_fold(v, m, n, axis=0), want)
    assert np.array_equal(_fold(v.T.copy(), m, n, axis=1), want.T)


def test_fold_of_non_consecutive_frequencies_scatters_them():
    m = np.array([0, 3, 7, -5, 12])
    v = np.arange(5) + 1j
    want = np.zeros(4, dtype=complex)
    for mi, vi in zip(m, v, strict=True):
        want[mi % 4] += vi
    np.testing.assert_allclose(_fold(v, m, 4, axis=0), want, atol=0)


def test_sampling_matrix_is_the_footprint_sum_of_exponentials():
    m, n = np.arange(-40, 41), 12000
    cases = [(np.array([3.2, 140.7, 9000.5]), w) for w in (1.0, 3.5, 14.0)]
    cases += [(6.5 + 14.0 * np.arange(5), 14.0), (7.0 + 14.0 * np.arange(5), 14.0)]  # integer ratio: alike footprints
    for centres, width in cases:
        idx, w = footprint_weights(centres, width, 0)
        want = (w[:, :, None] * np.exp(2j * np.pi * idx[:, :, None] * m[None, None, :] / n)).sum(axis=1)
        np.testing.assert_allclose(sampling_matrix(centres, width, 0, n, m), want, atol=1e-12)


@pytest.mark.parametrize(("value", "match"), [(np.nan, "NaN/inf"), (np.inf, "NaN/inf"), (1e300, "too large")])
def test_non_finite_or_float32_overflowing_input_is_refused(value, match):
    a = np.full((700, 700), 0.3)
    a[350, 5] = value
    with pytest.raises(InputError, match=match):
        simulate(a, load_preset("ankarasat3"), pixel_m=0.035)


@pytest.mark.parametrize("window", [(2, 2, 0, 3), (2, 2, 3, 0), (-2, 2, 0, 3), (12, 12, 0, 0)])
@pytest.mark.parametrize("rule", ["symmetric", "constant"])
def test_an_empty_window_reads_as_an_empty_array_of_its_shape(window, rule):
    """A window of height or width 0, inside the source or not, is an empty array of that shape (inside the
    source it once failed on the block it never read)."""
    src = ArraySource(np.arange(100.0).reshape(10, 10), pixel_m=1.0)
    out = read_with_border(src, Window(*window), rule=rule)
    assert out.shape == (window[2], window[3]) and out.dtype == np.float64
