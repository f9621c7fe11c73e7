"""The fast slanted-edge numerics against independent formulas (issue 21, point 2).

Nothing here is a value stored from the code under test: each fast path is compared with a different way of
computing the same quantity (finite differences of the forward MTF for the propagated noise, scipy's QR
least-squares spline and B-spline evaluation, ``np.linalg.lstsq`` per line, ``np.polyfit`` / ``np.median``,
direct complex exponentials).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import BSpline, make_lsq_spline
from scipy.special import ndtr

from satchain.errors import InputError
from satchain.measure._common import robust_sigma
from satchain.measure.edge import _crossings as lines
from satchain.measure.edge import _locate as locate
from satchain.measure.edge._numerics import _Lsf, adaptive_mtf, window_mtf


def _esf_bins(n_half: float, w: float, seed: int, noise: float):
    """A binned Gaussian-blurred ESF (bins of width w over +-n_half px) with noise, and its counts."""
    rng = np.random.default_rng(seed)
    x = np.arange(-n_half, n_half + w / 2, w) + 0.37 * w
    counts = rng.integers(5, 40, x.size)
    esf = ndtr(x / 0.7) + rng.normal(0.0, noise, x.size) / np.sqrt(counts)
    return x, esf, counts


def test_propagated_mtf_sigma_equals_finite_differences_of_the_forward_mtf():
    """The batched adjoint (with the shift theorem inside the kernel's reach) gives the same first-order noise
    as differentiating the forward map bin by bin: sigma(f)^2 = sum_k (d MTF(f) / d esf_k)^2 var_k."""
    sigma = 0.01
    for w, n_half, seed in ((0.25, 18.0, 1), (0.2887, 14.0, 2)):  # ISO bins, a lattice bin
        x, esf, counts = _esf_bins(n_half, w, seed, sigma)
        f = np.arange(0.0, 0.5 / w + 1e-9, 0.005)[: int(1.0 / 0.005) + 1]
        mtf, sig, half_w, _, _ = adaptive_mtf(x, esf, counts, sigma, f, noise_target=0.004)
        var = sigma**2 / counts
        h = 1e-6
        jac = np.empty((f.size, x.size))
        for k in range(x.size):
            e_p, e_m = esf.copy(), esf.copy()
            e_p[k] += h
            e_m[k] -= h
            diff = window_mtf(x, e_p, half_w, f[1:]) - window_mtf(x, e_m, half_w, f[1:])
            jac[:, k] = np.concatenate([[0.0], diff]) / (2 * h)
        sig_fd = np.sqrt((jac**2 * var[None, :]).sum(axis=1))
        assert np.allclose(mtf[1:], window_mtf(x, esf, half_w, f[1:]), rtol=0, atol=1e-12)
        assert np.allclose(sig[1:], sig_fd[1:], rtol=1e-5, atol=1e-9)


def test_window_noise_batch_equals_one_window_at_a_time():
    """All candidate windows in one pass give each window's own noise (the single-window map)."""
    x, esf, counts = _esf_bins(20.0, 0.25, 3, 0.01)
    var = 0.01**2 / counts
    f = np.array([0.0, 0.5])
    ws = np.array([20.0, 14.0, 9.0, 5.0])
    batch = _Lsf(x, ws, 0.25)
    specs = batch.spectrum(np.atleast_2d(batch.apply(esf)), f)
    noise = batch.mtf_sigma(specs, f, batch.fourier(f), var, np.sinc(f * 0.25))
    for k, hw in enumerate(ws):
        one = _Lsf(x, hw, 0.25)
        e = np.exp(-2j * np.pi * np.outer(f, one.xm))  # direct exponentials
        spec = e @ one.apply(esf) * 0.25
        assert np.allclose(specs[k], spec, rtol=0, atol=1e-13)
        assert np.allclose(noise[k], one.mtf_sigma(spec, f, e, var, np.sinc(f * 0.25)), rtol=1e-12, atol=1e-15)


def test_fourier_kernel_equals_direct_exponentials():
    op = _Lsf(np.arange(-30.0, 30.0, 0.23), 10.0, 0.23)
    for f in (np.arange(0.0, 1.0 + 1e-9, 0.005), np.array([0.0, 0.5]), np.linspace(0.0, 0.7, 37)):
        direct = np.exp(-2j * np.pi * np.outer(f, op.xm))
        assert np.max(np.abs(op.fourier(f) - direct)) < 1e-12


@settings(max_examples=25, deadline=None)
@given(n=st.integers(200, 3000), spacing=st.sampled_from([0.5, 0.625, 0.8]), seed=st.integers(0, 10**6))
def test_lsq_spline_equals_scipy_qr(n, spacing, seed):
    """Banded normal equations = scipy's QR least-squares spline; the basis = scipy's design matrix."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-12.0, 12.0, n)
    v = np.tanh(u / 1.3) + rng.normal(0.0, 0.01, n)
    lo, hi = u.min(), u.max()
    inner = np.arange(np.ceil(lo / spacing) * spacing, hi, spacing)
    inner = inner[(inner > lo + 0.5 * spacing) & (inner < hi - 0.5 * spacing)]
    knots = np.concatenate([[lo] * 4, inner, [hi] * 4])
    order = np.argsort(u)
    ref = make_lsq_spline(u[order], v[order], knots, k=3)
    fast = lines._lsq_spline(u, v, knots)
    assert np.max(np.abs(fast.c - ref.c)) < 1e-9
    first, vals = lines._basis(u, knots, len(knots) - 4)
    dm = BSpline.design_matrix(u, knots, 3).toarray()
    rows = np.arange(n)[:, None]
    assert np.allclose(dm[rows, first[:, None] + np.arange(4)], vals, rtol=0, atol=1e-13)
    assert np.allclose(dm.sum(axis=1), vals.sum(axis=1), rtol=0, atol=1e-13)  # no weight elsewhere
    uu = rng.uniform(lo, hi, 500)
    t, dt = lines._Cubic(ref)(uu)
    assert np.allclose(t, ref(uu), rtol=0, atol=1e-12)
    assert np.allclose(dt, ref.derivative()(uu), rtol=0, atol=1e-11)


def test_gauss_newton_step_equals_lstsq_per_line():
    rng = np.random.default_rng(5)
    t, dt, v = rng.normal(size=(3, 40, 13))
    a, c = rng.normal(size=40), rng.uniform(0.5, 2.0, 40)
    q = np.stack([np.ones_like(t), t, dt, v], axis=-1)
    gram = np.matmul(q.transpose(0, 2, 1), q)
    step = lines._solve(gram, a, c)
    rss = lines._rss(gram, a, c)
    jtj = lines._normal(gram, c)
    a_ls, c_ls = lines._levels(gram)
    for i in range(40):
        jac = np.stack([np.ones(13), t[i], -c[i] * dt[i]], axis=1)
        r = v[i] - a[i] - c[i] * t[i]
        assert np.allclose(step[i], np.linalg.lstsq(jac, r, rcond=None)[0], rtol=1e-10, atol=1e-12)
        assert np.isclose(rss[i], r @ r, rtol=1e-10)
        assert np.allclose(jtj[i], jac.T @ jac, rtol=1e-12, atol=1e-12)
        assert np.isclose(lines._inv22((jac.T @ jac)[None], np.array([True]))[0], np.linalg.inv(jac.T @ jac)[2, 2])
        assert np.allclose([a_ls[i], c_ls[i]], np.polyfit(t[i], v[i], 1)[::-1], rtol=1e-10, atol=1e-12)
    # a line whose profile has no slope (T' = 0) or no contrast (c = 0) is singular: no step, no NaN
    q[0, :, 2] = 0.0
    c[1] = 0.0
    step = lines._solve(np.matmul(q.transpose(0, 2, 1), q), a, c)
    assert np.array_equal(step[:2], np.zeros((2, 3)))
    assert np.all(np.isfinite(step))


@settings(max_examples=30, deadline=None)
@given(n=st.integers(1, 60), seed=st.integers(0, 10**6))
def test_median_and_robust_sigma_equal_numpy(n, seed):
    v = np.random.default_rng(seed).normal(size=n)
    assert locate._median(v) == np.median(v)
    assert locate._robust_sigma(v) == robust_sigma(v)


@settings(max_examples=30, deadline=None)
@given(deg=st.integers(1, 3), n=st.integers(12, 120), seed=st.integers(0, 10**6))
def test_robust_polyfit_equals_ten_plain_reweightings(deg, n, seed):
    """The lean fit (stopping once it moves by < 1e-6 px, or a given tolerance) = ten Tukey reweightings with
    np.polyfit / np.median, to the ~0.2 x tolerance the reweightings left would still move it (each move
    ~0.1-0.15 x the last)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n, dtype=float)
    y = 30.0 + 0.1 * t + 1e-4 * (t - n / 2) ** 2 + rng.normal(0.0, 0.1, n)
    y[rng.integers(0, n, max(1, n // 10))] += 5.0  # outliers
    w = np.ones(n)
    coef = np.polyfit(t, y, deg)
    for _ in range(10):
        r = y - np.polyval(coef, t)
        u = r / (4.685 * max(robust_sigma(r), 0.05))
        w = np.where(np.abs(u) < 1, (1 - u * u) ** 2, 0.0)
        if np.count_nonzero(w) <= deg + 2:  # too few inliers left: refused
            with pytest.raises(InputError, match="no straight edge"):
                locate.robust_polyfit(t, y, deg)
            return
        coef = np.polyfit(t, y, deg, w=np.sqrt(w))
    # the weights are those of the fit before the last, up to ~10 x the last move (< bound) from the converged
    # fit: a residual moved by D (and the robust sigma, by <= 2 x 1.4826 D) moves a Tukey weight by at most
    # max |dw/du| (1.54) x (D + 4.685 x 3 D) / (4.685 s) < 5 D / s
    s = max(robust_sigma(y - np.polyval(coef, t)), 0.05)
    for tol, bound in ((None, 1e-6), (1e-8, 1e-7)):
        fast, w_fast = locate.robust_polyfit(t, y, deg) if tol is None else locate.robust_polyfit(t, y, deg, tol=tol)
        assert np.max(np.abs(np.polyval(fast, t) - np.polyval(coef, t))) < bound
        assert np.max(np.abs(w_fast - w)) < 5 * (10 * bound) / s
