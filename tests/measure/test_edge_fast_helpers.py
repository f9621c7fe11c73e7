"""The vectorised / closed-form helpers of the fast slanted-edge and edge-search paths (issue 21, point 2)
against their plain references: ``np.polyfit`` / ``np.polyval``, a sorted phase gap, ``np.median``,
``np.linalg.lstsq`` / ``pinv``, one-shot Fourier kernels and direct mirrored convolutions,
``scipy.ndimage.gaussian_filter`` and the gradient recomputed on each segment's padded crop.

Not timed: the speed is printed by ``benchmarks/bench_edge_speed.py``.
"""

from __future__ import annotations

import numpy as np
from _render_chart import render_chart
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage as ndi

from satchain.errors import InputError
from satchain.measure import find
from satchain.measure._common import median, robust_sigma
from satchain.measure.edge import _checks as checks
from satchain.measure.edge import _crossings as lines
from satchain.measure.edge import _locate as locate
from satchain.measure.edge._numerics import _Lsf, _spectrum_sigma_direct, spectrum_sigma


@settings(max_examples=40, deadline=None)
@given(
    deg=st.integers(1, 3),
    n=st.integers(6, 200),
    t0=st.sampled_from([0.0, 37.0, 3900.0]),
    zeros=st.floats(0.0, 0.5),
    seed=st.integers(0, 10**6),
)
def test_moment_polyfit_equals_np_polyfit(deg, n, t0, zeros, seed):
    """Weighted polynomial fits by moments in the centred variable = np.polyfit's QR solution (values and
    np.polyval coefficients), on rows far from the origin and with zero weights."""
    rng = np.random.default_rng(seed)
    t = t0 + np.sort(rng.choice(np.arange(4 * n), n, replace=False)).astype(float)
    y = 20.0 + 0.07 * (t - t0) + 2e-4 * (t - t0 - n) ** 2 + rng.normal(0.0, 0.3, n)
    w = rng.uniform(0.0, 1.0, n)
    w[rng.uniform(size=n) < zeros] = 0.0
    if np.count_nonzero(w) < deg + 2:
        w[: deg + 2] = 1.0
    poly = locate._Poly(t, deg)
    scale = np.max(np.abs(y))
    for weights in (None, w):
        sw = None if weights is None else np.sqrt(weights)
        q = poly.fit(y, deg, weights)
        # the reference: np.polyfit's QR least squares, in t - mean(t) (in raw t it is itself ill-conditioned
        # far from the origin; the edge fits use a region's rows, 0 to a few hundred)
        tm = t - t.mean()
        ref = np.polyval(np.polyfit(tm, y, deg, w=sw), tm)
        assert np.max(np.abs(poly.value(q) - ref)) < 1e-10 * scale
        coef = poly.coef(q)  # np.polyval coefficients in t: exact to the evaluation's own rounding
        powers = np.abs(t[:, None]) ** np.arange(deg, -1, -1)[None, :]
        assert np.all(np.abs(np.polyval(coef, t) - ref) <= 1e-10 * scale + 1e-14 * (powers @ np.abs(coef)))
        if t0 < 1000:
            assert np.max(np.abs(poly.value(q) - np.polyval(np.polyfit(t, y, deg, w=sw), t))) < 1e-9 * scale


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 9000), spread=st.floats(0.02, 1.0), clusters=st.integers(1, 6), seed=st.integers(0, 10**6))
def test_phase_gap_bound_decides_as_the_exact_gap(n, spread, clusters, seed):
    """The largest sub-pixel phase gap: exact up to 4096 lines (sorted), above exact where it can matter
    (> 25/64 px), else a bound between the exact gap and 25/64 (< 0.4 px: no refusal, knots unchanged) -- the
    template's decisions are the exact ones."""
    rng = np.random.default_rng(seed)
    u = rng.integers(-15, 15, n) + (rng.integers(0, clusters, n) / clusters + rng.uniform(0, spread / 10, n))
    frac = np.sort(np.mod(u, 1.0))
    exact = float(np.max(np.diff(np.concatenate([frac, frac[:1] + 1.0]))))
    fast = lines._phase_gap(u)
    if n <= lines._SORT_PHASES:
        assert fast == exact
    if fast > 25 / 64:
        assert fast == exact
    else:
        assert exact <= fast + 1e-15 <= 25 / 64 + 1e-15


@settings(max_examples=40, deadline=None)
@given(
    n_lines=st.integers(1, 150),
    spread=st.floats(0.02, 1.0),
    clusters=st.integers(1, 6),
    keep=st.floats(0.0, 1.0),
    seed=st.integers(0, 10**6),
)
def test_template_phase_gap_from_lines_equals_the_samples_gap(n_lines, spread, clusters, keep, seed):
    """The template's phase gap from one phase per line (its samples sit at whole columns): the same
    decision as the gap of every sample ``cols - place`` (those taken): equal to rounding where exact."""
    rng = np.random.default_rng(seed)
    place = 40.0 + rng.integers(-10, 10, n_lines) + rng.integers(0, clusters, n_lines) / clusters
    place = place + rng.uniform(0, spread / 10, n_lines)
    cols = np.rint(place)[:, None] + np.arange(-8, 9)[None, :]
    take = rng.uniform(size=cols.shape) < keep
    u = (cols - place[:, None])[take]
    per_line = lines._phase_gap(-place[take.any(axis=1)])
    if u.size == 0:
        assert per_line == lines._phase_gap(u) == 1.0
        return
    frac = np.sort(np.mod(u, 1.0))
    exact = float(np.max(np.diff(np.concatenate([frac, frac[:1] + 1.0]))))
    if per_line > 25 / 64:
        assert abs(per_line - exact) < 1e-12
    else:
        assert exact <= per_line + 1e-12 <= 25 / 64 + 1e-12


@settings(max_examples=40, deadline=None)
@given(
    shape=st.sampled_from([(1,), (2,), (7,), (10, 3), (101,), (256,), (257,), (17, 30)]),
    nan=st.booleans(),
    seed=st.integers(0, 10**6),
)
def test_median_equals_np_median(shape, nan, seed):
    v = np.random.default_rng(seed).normal(size=shape)
    if nan:
        v.flat[0] = np.nan
    m = median(v)
    assert (np.isnan(m) and np.isnan(np.median(v))) or m == np.median(v)
    if not nan:
        w = v.ravel()
        assert robust_sigma(v) == 1.482602218505602 * np.median(np.abs(w - np.median(w)))
        assert robust_sigma(w.copy(), overwrite=True) == robust_sigma(v)  # (the caller's own array reused)


@settings(max_examples=30, deadline=None)
@given(n=st.integers(4, 60), k=st.floats(0.0, 0.3), b=st.floats(-0.01, 0.01), seed=st.integers(0, 10**6))
def test_plateau_line_equals_lstsq_with_pinv_errors(n, k, b, seed):
    """Level and slope of a plateau by scaled normal equations = the QR least squares with pinv standard errors
    (the same terms taken, the same coefficients)."""
    rng = np.random.default_rng(seed)
    xs = np.sort(rng.uniform(4.0, 40.0, n)) * rng.choice([-1, 1])
    es = 0.8 + b * xs + k / np.abs(xs) + rng.normal(0.0, 0.002, n)

    def fit(cols):  # (smallest |t| beyond the level, level, slope or 0)
        m = np.stack(cols, axis=1)
        coef = np.linalg.lstsq(m, es, rcond=None)[0]
        s2 = float(np.sum((es - m @ coef) ** 2)) / max(xs.size - len(cols), 1)
        t = np.abs(coef[1:]) / np.sqrt(np.maximum(np.diag(np.linalg.pinv(m.T @ m)) * s2, 1e-300))[1:]
        return float(t.min()), float(coef[0]), float(coef[1]) if cols[1] is xs else 0.0

    def reference(xs, es):  # forward selection: a term enters where resolved on its own (|t| >= 3)
        one, ax_s = np.ones_like(xs), np.abs(xs)
        extra = [xs] if xs.size >= 8 and np.ptp(xs) > 2.0 else []
        if extra and xs.size >= 12 and ax_s.max() > 3 * ax_s.min():
            extra.append(1.0 / ax_s)
        best = (float(es.mean()), 0.0)
        if extra:
            t, a, s = max((fit([one, c]) for c in extra), key=lambda r: r[0])
            if t >= 3.0:
                best = (a, s)
                if len(extra) == 2 and fit([one, *extra])[0] >= 3.0:
                    best = fit([one, *extra])[1:]
        return best

    fast, ref = checks._plateau_line(xs, es), reference(xs, es)
    assert abs(fast[0] - ref[0]) < 1e-10 and abs(fast[1] - ref[1]) < 1e-11


def test_chunked_spectrum_and_noise_equal_one_pass():
    """The output band in chunks (Fourier kernel, spectrum, propagated noise with the normalisation given) =
    the one-pass forms; the smoothing's end matrices = the mirrored convolution itself."""
    rng = np.random.default_rng(4)
    for w in (0.25, 0.2887):
        x = np.arange(-25.0, 25.0, w) + 0.1 * w
        op = _Lsf(x, 12.0, w)
        lsf = np.exp(-0.5 * (op.xm / 0.8) ** 2) + rng.normal(0.0, 1e-3, op.xm.size)
        f = np.arange(0.0, 0.5 / w + 1e-9, 0.005)[:201]
        e_all = op.fourier(f)
        var = rng.uniform(0.5, 2.0, x.size) * 1e-6
        spec_all = op.spectrum(lsf, f, e_all)
        sig_all = op.mtf_sigma(spec_all, f, e_all, var, np.sinc(f * w))
        for sl, e in op.fourier_chunks(f):
            assert np.max(np.abs(e - np.exp(-2j * np.pi * np.outer(f[sl], op.xm)))) < 1e-12
            spec = op.spectrum(lsf, f[sl], e)
            assert np.allclose(spec, spec_all[sl], rtol=0, atol=1e-14)
            sig = op.mtf_sigma(spec, f[sl], e, var, np.sinc(f[sl] * w), m0=spec_all[0].real)
            assert np.allclose(sig, sig_all[sl], rtol=1e-12, atol=1e-16)
        p = rng.normal(size=(5, op.xm.size))
        assert np.allclose(op._s_fourier(p, f[:5]), _s_fourier_direct(op, p, f[:5]), rtol=0, atol=1e-14)


@settings(max_examples=40, deadline=None)
@given(
    w=st.sampled_from([0.25, 0.125, 0.2887, 0.3, 0.0625, 0.71 / 3]),
    half_w=st.floats(3.0, 30.0),
    span=st.floats(12.0, 40.0),
    blur=st.floats(0.3, 3.0),
    sign=st.sampled_from([1.0, -1.0]),
    f_top=st.sampled_from([0.5, 1.0, 2.0]),
    seed=st.integers(0, 10**6),
)
def test_closed_form_spectrum_sigma_equals_direct_pass(w, half_w, span, blur, sign, f_top, seed):
    """The spectrum and MTF noise from one Fourier transform of the LSF and six weighted window moments (the
    ends propagated directly) = the direct pass over every frequency and bin, on real (FFT) and chirp-z
    step ratios, short windows, ESFs too short for the interior form (direct fallback) and falling edges."""
    rng = np.random.default_rng(seed)
    x = np.arange(-span, span, w) + rng.uniform(-0.5, 0.5) * w
    op = _Lsf(x, min(half_w, span - w), w)
    lsf = sign * np.exp(-0.5 * (op.xm / blur) ** 2) + rng.normal(0.0, 1e-3, op.xm.size)
    f = np.arange(0.0, min(f_top, 0.5 / w) + 1e-9, 0.005)
    var = rng.uniform(0.2, 3.0, x.size) * 1e-6
    corr = np.sinc(f * w)
    spec, sig = spectrum_sigma(op, lsf, f, var, corr)
    spec_ref, sig_ref = _spectrum_sigma_direct(op, lsf, f, var, corr)
    assert np.max(np.abs(spec - spec_ref)) < 1e-11 * np.max(np.abs(spec_ref))
    assert np.all(np.abs(sig - sig_ref) <= 1e-9 * sig_ref + 1e-15)


def _s_fourier_direct(op, p, f):
    """The previous form: the kernel's transfer inside, the mirrored convolution itself at the ends."""
    k = op.kernel
    r = k.size // 2
    h = k[r] + 2.0 * np.cos(2 * np.pi * np.outer(f, np.arange(1, r + 1) * op.w)) @ k[r + 1 :]
    out = h[:, None] * p
    out[:, :r] = op._s(p[:, : 2 * r + 1])[:, :r]
    out[:, -r:] = op._s(p[:, -(2 * r + 1) :])[:, -r:]
    return out


def test_uniform_knot_index_equals_search():
    """The spline's knot interval by arithmetic = np.searchsorted (off the knots), the same values at them."""
    rng = np.random.default_rng(2)
    u = np.sort(rng.uniform(-12.0, 12.0, 3000))
    v = np.tanh(u / 1.1) + rng.normal(0.0, 0.01, u.size)
    inner = np.arange(-11.5, 11.6, 0.5)
    spline = lines._lsq_spline(u, v, np.concatenate([[u[0]] * 4, inner, [u[-1]] * 4]))
    cubic = lines._Cubic(spline)
    assert cubic.uniform
    uu = np.concatenate([rng.uniform(u[0] - 1, u[-1] + 1, 2000), inner])
    ref = np.clip(np.searchsorted(cubic.bx, uu, side="right") - 1, 0, cubic.bx.size - 2)
    off_knot = ~np.isin(uu, inner)
    assert np.array_equal(cubic.index(uu)[off_knot], ref[off_knot])
    t, dt = cubic(np.clip(uu, u[0], u[-1]))
    assert np.allclose(t, spline(np.clip(uu, u[0], u[-1])), rtol=0, atol=1e-12)
    assert np.allclose(dt, spline.derivative()(np.clip(uu, u[0], u[-1])), rtol=0, atol=1e-11)


@settings(max_examples=20, deadline=None)
@given(ny=st.integers(3, 80), nx=st.integers(3, 80), sigma=st.sampled_from([1.0, 1.5]), seed=st.integers(0, 10**6))
def test_find_gaussian_equals_ndimage_bitwise(ny, nx, sigma, seed):
    a = np.random.default_rng(seed).normal(size=(ny, nx)).astype(np.float32)
    for orders in ((0, 0), (0, 1), (1, 0)):
        ref = ndi.gaussian_filter(a, sigma, order=orders, mode="nearest")
        assert np.array_equal(find._gaussian(a, sigma, orders), ref)


def test_segment_gradients_equal_each_segments_own_crop():
    """The gradient each segment takes from the search bands = the gradient of its own padded crop (the old
    per-segment refiltering), bit for bit, with bands cut across the segments."""
    rng = np.random.default_rng(9)
    squares = [
        (60 + 110 * j + rng.uniform(0, 1), 60 + 110 * i + rng.uniform(0, 1), 60, rng.uniform(3, 12))
        for i in range(2)
        for j in range(2)
    ]
    img = render_chart((240, 240), squares, sx=0.5, sy=0.6, noise=0.004, rng=rng).astype(np.float32)
    mask, grads = find._edge_mask(img, 0.01, 64)
    segs = find._segments(img, mask, 12.0, grads)
    assert len(segs) >= 8
    labels, _ = ndi.label(mask, structure=np.ones((3, 3), dtype=int))
    for seg in segs:
        yy, xx = seg.ys.astype(int), seg.xs.astype(int)
        y0, y1 = max(0, yy.min() - find._PAD), min(img.shape[0], yy.max() + 1 + find._PAD)
        x0, x1 = max(0, xx.min() - find._PAD), min(img.shape[1], xx.max() + 1 + find._PAD)
        crop = img[y0:y1, x0:x1]
        gx = ndi.gaussian_filter(crop, find._GRAD_SIGMA, order=(0, 1), mode="nearest")[yy - y0, xx - x0]
        gy = ndi.gaussian_filter(crop, find._GRAD_SIGMA, order=(1, 0), mode="nearest")[yy - y0, xx - x0]
        assert np.array_equal(seg.w, gx.astype(float) ** 2 + gy.astype(float) ** 2)
        assert np.array_equal(seg.gang, np.arctan2(gy.astype(float), gx.astype(float)))


@settings(max_examples=30, deadline=None, derandomize=True)
@given(n=st.integers(8, 420), m=st.integers(1, 210), step=st.floats(0.001, 0.05), seed=st.integers(0, 999))
def test_dft_rows_equals_the_direct_sum(n, m, step, seed):
    """The spectrum rows at ``j step`` cy/bin: a real FFT where it fits, else the factorised matrix DFT, both equal
    to the plain sum of ``rows[k] exp(-2 pi i j step k)``."""
    from satchain.measure.edge._numerics import _dft_rows

    rows = np.random.default_rng(seed).normal(size=(2, n))
    direct = rows @ np.exp(-2j * np.pi * np.outer(np.arange(m) * step, np.arange(n))).T
    np.testing.assert_allclose(_dft_rows(rows, step, m), direct, rtol=0, atol=1e-10 * np.abs(rows).sum())


@settings(max_examples=40, deadline=None)
@given(n=st.integers(2, 400), t0=st.sampled_from([0.0, 50.0, 3000.0]), seed=st.integers(0, 10**6))
def test_flatten_line_fit_equals_polyfit(n, t0, seed):
    """The row flattening's straight line (centred closed form) = ``np.polyval(np.polyfit(t, y, 1), at)``."""
    from satchain.measure.edge._numerics import _line_fit

    rng = np.random.default_rng(seed)
    t = t0 + np.sort(rng.choice(np.arange(4 * n), n, replace=False)).astype(float)
    y = rng.normal(1.0, 0.3, n) + 1e-3 * t
    at = t0 + np.arange(4 * n, dtype=float)
    ref = np.polyval(np.polyfit(t, y, 1), at)
    assert np.max(np.abs(_line_fit(t, y, at) - ref)) < 1e-10 * (1.0 + np.max(np.abs(ref)))


@settings(max_examples=30, deadline=None)
@given(
    ny=st.integers(1, 40),
    nx=st.integers(1, 40),
    k=st.integers(1, 9),
    transposed=st.booleans(),
    seed=st.integers(0, 10**6),
)
def test_row_take_equals_take_along_axis(ny, nx, k, transposed, seed):
    """The line fits' flat gather = ``np.take_along_axis(a, kc, axis=1)``, on a transposed (ALT) view too."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(nx, ny)).T if transposed else rng.normal(size=(ny, nx))
    kc = rng.integers(0, nx, (ny, k))
    np.testing.assert_array_equal(a.take(lines._row_take(kc, nx)), np.take_along_axis(a, kc, axis=1))
    ok = a > 0
    np.testing.assert_array_equal(ok.take(lines._row_take(kc, nx)), np.take_along_axis(ok, kc, axis=1))


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(1, 12000),
    levels=st.sampled_from([None, 2, 30, 255, 4096]),
    scale=st.sampled_from([1.0, 1 / 255, 1e-9, 1e6]),
    signed_zero=st.booleans(),
    seed=st.integers(0, 10**6),
)
def test_distinct_lower_bound_bounds_np_unique(n, levels, scale, signed_zero, seed):
    """The hashed count of distinct values never exceeds np.unique's (so it only ever proves data continuous),
    at least one, near n for continuous data; and the quantisation step is unchanged by it."""
    rng = np.random.default_rng(seed)
    x = rng.normal(0.5, 0.2, n) if levels is None else rng.integers(0, levels, n).astype(float)
    x *= scale
    if signed_zero:
        x[: n // 3] = 0.0
        x[n // 3 : n // 2] = -0.0
    exact = np.unique(x).size
    bound = checks.distinct_lower_bound(x)
    assert bound <= exact
    assert bound >= 1
    if levels is None and not signed_zero and n >= 100:
        assert bound >= 0.9 * exact
    assert checks.quantisation_step(x) == checks.quantisation_step(x, unique=np.unique(x))


@settings(max_examples=30, deadline=None)
@given(n=st.integers(3, 400), sigma=st.floats(0.5, 6.0), step=st.floats(0.05, 2.0), seed=st.integers(0, 10**6))
def test_bin_esf_smoothing_and_gradient_equal_scipy_and_numpy_bitwise(n, sigma, step, seed):
    """The ESF's bin-position correction smooths with gaussian_filter1d's own kernel and differentiates as
    np.gradient does: the same floats."""
    from scipy.ndimage import correlate1d

    from satchain.measure.edge._numerics import _gauss_kernel_nd, _gradient

    a = np.cumsum(np.random.default_rng(seed).normal(size=n))
    ref = ndi.gaussian_filter1d(a, sigma, mode="nearest")
    assert np.array_equal(correlate1d(a, _gauss_kernel_nd(sigma), mode="nearest"), ref)
    assert np.array_equal(_gradient(a, step), np.gradient(a, step))


@settings(max_examples=30, deadline=None)
@given(
    ny=st.integers(8, 60),
    nx=st.integers(20, 90),
    slope=st.floats(-0.6, 0.6),
    x0=st.floats(-10.0, 100.0),
    half=st.integers(3, 12),
    seed=st.integers(0, 10**6),
)
def test_ridge_centroids_equal_full_row_windows(ny, nx, slope, x0, half, seed):
    """The derivative centroids from each line's band of 2 half + 1 columns = those of the whole row masked
    to |column - centre| <= half (the earlier form), for the lines whose window lies inside the region."""
    rng = np.random.default_rng(seed)
    g = rng.uniform(0.0, 1.0, (ny, nx))
    coef = np.array([slope, x0])
    rows = np.arange(ny, dtype=float)
    centre = np.polyval(coef, rows)
    keep = (centre - half >= 1) & (centre + half <= nx - 2)
    if np.count_nonzero(keep) < locate.MIN_ROWS:
        return
    cols = np.arange(nx, dtype=float)
    gw = np.where(np.abs(cols[None, :] - centre[:, None]) <= half, g, 0.0)[keep]
    ref = (gw * cols).sum(axis=1) / gw.sum(axis=1)
    r_used, cen, tot, n_keep = locate.ridge_centroids(g, g, coef, half)
    assert n_keep == np.count_nonzero(keep)
    assert np.array_equal(r_used, rows[keep])
    assert np.allclose(cen, ref, rtol=0, atol=1e-12 * nx)
    assert np.allclose(tot, gw.sum(axis=1), rtol=1e-13)


@settings(max_examples=40, deadline=None)
@given(s0=st.floats(1e-4, 0.3), rate=st.floats(0.001, 0.9), n=st.integers(1, 50), seed=st.integers(0, 10**6))
def test_gauss_newton_stops_once_the_geometric_tail_is_below_the_tolerance(s0, rate, n, seed):
    """Steps shrinking by ``rate`` each: converged exactly when the steps still to come, ``s r / (1 - r)``,
    are below the tolerance (or the step itself is); the true remaining movement is then below it too.  A line
    whose step grows is not converged while its step is above the tolerance."""
    tol = lines._TOL_STEP
    rng = np.random.default_rng(seed)
    scale = rng.uniform(0.5, 2.0, (n, 1))  # the lines differ in their first step
    prev = s0 * scale * np.ones((n, 3))
    tol_ac = np.full((n, 1), tol)
    for _ in range(40):
        s = prev * rate
        done = lines._converged(s, prev, tol_ac)
        tail = s * rate / (1 - rate)
        assert done == bool(np.all(np.minimum(tail, s) < tol))
        if done:
            assert np.all(np.minimum(tail, s) < tol)
            break
        prev = s
    grow = prev.copy()
    grow[0, 2] = 1.5 * prev[0, 2]  # one line's position step grows
    assert lines._converged(grow, prev, tol_ac) == bool(grow[0, 2] < tol and np.all(grow < tol))


@settings(max_examples=40, deadline=None)
@given(
    slope=st.floats(-0.5, 0.5),
    x0=st.floats(20.0, 40.0),
    nudge=st.floats(-0.3, 0.3),
    half=st.integers(4, 12),
    seed=st.integers(0, 10**6),
)
def test_equal_window_bounds_give_equal_ridge_centroids(slope, x0, nudge, half, seed):
    """The edge search stops when a new fit leaves every line's window bounds as they were: the centroids
    (and every output of ridge_centroids) are then the same, bit for bit; different bounds are told apart."""
    rng = np.random.default_rng(seed)
    g = rng.uniform(0.0, 1.0, (40, 60))
    valid = rng.uniform(size=g.shape) > 0.02
    rows = np.arange(40, dtype=float)
    a, b = np.array([slope, x0]), np.array([slope, x0 + nudge * 1e-3])
    same = np.array_equal(locate._window_bounds(a, rows, half), locate._window_bounds(b, rows, half))
    for v in (None, valid):
        try:
            ra = locate.ridge_centroids(g, g, a, half, v)
            rb = locate.ridge_centroids(g, g, b, half, v)
        except InputError:  # (too few lines kept: refused alike when the bounds are equal)
            continue
        if same:
            assert all(np.array_equal(p, q) for p, q in zip(ra, rb, strict=True))
    far = np.array([slope, x0 + 1.0])  # a whole pixel: every bound moves
    assert not np.array_equal(locate._window_bounds(a, rows, half), locate._window_bounds(far, rows, half))


@settings(max_examples=30, deadline=None)
@given(n=st.integers(2, 120), t0=st.sampled_from([0.0, 37.0]), seed=st.integers(0, 10**6))
def test_nested_degree_fits_equal_each_degree_fitted_alone(n, t0, seed):
    """pick_degree's fits of degree 1, 2 and 3 from one Cholesky factor (a lower degree's matrix is the
    leading block) = each fitted on its own, to rounding; degenerate abscissae (fewer points than terms) alike."""
    rng = np.random.default_rng(seed)
    t = t0 + np.sort(rng.choice(np.arange(3 * n), n, replace=False)).astype(float)
    y = 5.0 + 0.1 * t + rng.normal(0.0, 0.3, n)
    poly = locate._Poly(t)
    nested = poly.nested_fits(y)
    for k in (1, 2, 3):
        alone = poly.value(poly.fit(y, k))
        assert np.allclose(nested[k], alone, rtol=0, atol=1e-12 * (1 + np.abs(y).max()))
