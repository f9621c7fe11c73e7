"""Streamed simulation: inputs whose coarse frame does not fit in memory (a 100000 x 100000 TIFF, say).

The full-frame stage 2 (:meth:`Simulator.form_image`) transforms the whole coarse frame at once, which needs
``~20 bytes x (input / D^2)`` of memory. The streamed path bounds every stage instead:

1. stage 1 writes the coarse grid into a disk-backed array (:func:`coarse_store`, a ``.npy`` memory map in a
   scratch folder removed afterwards) instead of memory;
2. stage 2 forms the image tile by tile (:meth:`Simulator.form_tile`): each output tile of
   ``SimParams.stream_tile_px`` from the coarse frame's window reaching ``SimParams.stream_margin_px`` output
   pixels beyond it (the frame follows the same border rule as the full-frame path). The PSF's tail beyond
   the margin is wrapped around the window instead of taken from the scene -- the only difference from the
   full-frame result (measured by ``benchmarks/bench_stream.py``);
3. the sensor runs per tile on the fixed noise-block grid (:mod:`satchain.engine.sensor`), so the noise is
   bit-identical to the full-frame path's, and the image is written band by band into a tiled (Big)TIFF:
   it is never held whole either.

:func:`choose_streamed` picks this path when the full-frame path would exceed the memory limit.
"""

from __future__ import annotations

import contextlib
import math
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, Literal

import numpy as np

from satchain.engine.sensor import SensorModel
from satchain.engine.simulate import _FRAME_BYTES_PER_PX, Simulator
from satchain.engine.spectral import LOWPASS_SUPPORT, band_index
from satchain.errors import ConfigError

__all__ = [
    "FarField",
    "choose_streamed",
    "coarse_store",
    "far_split",
    "simulate_to_tiff",
    "stream_bytes",
    "stream_tile_px",
    "stream_tiles",
    "write_streamed",
]

Progress = Callable[[int, int], None]
#: bytes per output pixel of one tile: the complex128 fold, the float64 image, sensor temporaries
_TILE_OUT_BYTES_PER_PX = 64
#: frame rows read at once while the far field is built (float32 bytes)
_FAR_BAND_BYTES = 64 * 2**20
#: longest side of the streamed PNG preview (a strided subsample of the image)
PREVIEW_MAX_PX = 4096


def stream_tile_px(sim: Simulator) -> int:
    """The output tile side actually used: ``SimParams.stream_tile_px`` rounded up to a multiple of the
    noise block and of the output period on which tile windows start on the coarse grid (integer ``k``)."""
    p = sim.params
    step = int(p.noise_block_px)
    for ki in sim.k_int:
        if ki:
            step = math.lcm(step, sim.D // math.gcd(ki, sim.D))
    return -(-int(p.stream_tile_px) // step) * step


def stream_bytes(sim: Simulator) -> float:
    """Estimated peak bytes of the streamed path (the coarse grid on disk is not counted): one decimation
    tile or one stage-2 window with its tile's temporaries, plus one output band and the preview."""
    t, m = stream_tile_px(sim), int(sim.params.stream_margin_px)
    window = min(_window_bytes(sim, m), sim.frame_bytes)
    decim = min(float(sim.params.max_tile_bytes), 20.0 * (sim.D * sim.n_coarse[0]) * (sim.D * sim.n_coarse[1]))
    band = 8.0 * t * sim.output_shape[1]
    preview = 8.0 * min(PREVIEW_MAX_PX**2, float(sim.output_shape[0]) * sim.output_shape[1])
    # the far field: its band of the frame (complex64, the transform's copy and the kept rows), one band of
    # frame rows with its real FFT while it is built, and per tile the two sampling matrices and a product --
    # or, on an output grid that divides the frame, the band on every output row and one band of output rows
    ly, lx = sim.frame_shape
    by, bx = (band_index(n, far_split(sim, m)) for n in (ly, lx))
    noy, nox = (n * sim.D / kk for n, kk in zip(sim.frame_shape, sim.k, strict=True))
    far = 8.0 * (2 * ly + 2 * by + 1) * (bx + 1) + 16.0 * t * (2 * by + 2 * bx + 2)
    far += 16.0 * noy * (bx + 1) + 40.0 * t * nox
    build = 3.0 * _FAR_BAND_BYTES
    return max(window + _TILE_OUT_BYTES_PER_PX * 1.5 * t * t, decim, build) + far + band + preview


def _window_bytes(sim: Simulator, margin_px: int) -> float:
    """Working memory of the widest stage-2 tile's window (:func:`_col_spans`), bytes."""
    t = stream_tile_px(sim)
    _, shape = sim.tile_window((0, t), (0, t + t // 2), margin_px)
    return _FRAME_BYTES_PER_PX * float(shape[0]) * shape[1]


def far_split(sim: Simulator, margin_px: int) -> float:
    """Where :class:`FarField` splits the OTF, cycles per coarse sample: ``2 x LOWPASS_SUPPORT / margin``
    (the margin in coarse samples), so the low-pass's kernel lies within half the tile margin."""
    m_coarse = min(max(int(margin_px), 1) * kk / sim.D for kk in sim.k)
    return min(2 * LOWPASS_SUPPORT / m_coarse, sim.f_cut * sim.D)


def choose_streamed(sim: Simulator, *, focal_plane: str | None = None, limit_bytes: float | None = None) -> bool:
    """True when the full-frame path would not fit (its estimate, :func:`satchain.engine.memory.simulation_bytes`,
    above ``limit_bytes`` -- default :func:`satchain._safety.memory_limit_bytes` -- or its coarse frame above
    ``SimParams.max_frame_bytes``) while the streamed path would. Only the plan is looked at; nothing is
    allocated. The focal-plane image needs the whole coarse frame, so it never streams.

    Examples
    --------
    >>> from satchain import load_preset
    >>> big = Simulator(load_preset("ankarasat3"), input_pixel_m=0.035, input_shape=(100_000, 100_000))
    >>> small = Simulator(load_preset("ankarasat3"), input_pixel_m=0.035, input_shape=(2000, 2000))
    >>> choose_streamed(big, limit_bytes=8 * 2**30), choose_streamed(small, limit_bytes=8 * 2**30)
    (True, False)
    """
    from satchain._safety import memory_limit_bytes
    from satchain.engine.memory import simulation_bytes

    limit = memory_limit_bytes() if limit_bytes is None else float(limit_bytes)
    if focal_plane is not None or min(sim.k) < 1:  # an output finer than the input is not a streaming job
        return False
    full_fits = simulation_bytes(sim) <= limit and sim.frame_bytes <= sim.params.max_frame_bytes
    return not full_fits and stream_bytes(sim) <= limit


@contextlib.contextmanager
def coarse_store(
    sim: Simulator, directory: str | os.PathLike | None = None, *, prefix: str = ".satchain-coarse-"
) -> Iterator[np.ndarray]:
    """A disk-backed float32 array of the coarse grid's shape (``numpy.lib.format.open_memmap``) in a new
    scratch folder ``prefix*`` inside ``directory`` (default: :func:`tempfile.gettempdir`), owned by this
    process (:func:`satchain._safety.claim`: a killed run's folder is removed by the next run's
    :func:`satchain._safety.clean_stale`); the folder is removed on exit."""
    from satchain._safety import claim

    d = Path(tempfile.mkdtemp(prefix=prefix, dir=directory))
    try:
        claim(d)
        arr = np.lib.format.open_memmap(d / "coarse.npy", mode="w+", dtype=np.float32, shape=sim.n_coarse)
        if sim.yaw_deg:  # the rotated frame (engine.yaw) beside it, on disk too
            sim.yaw_store = lambda shape: np.lib.format.open_memmap(
                d / "yawed.npy", mode="w+", dtype=np.float32, shape=shape
            )
        yield arr
        del arr
    finally:
        if sim.yaw_deg:
            sim.yaw_store, sim._yaw_cache = None, None
        shutil.rmtree(d, ignore_errors=True)


class FarField:
    """The long-range part of stage 2 over the whole coarse frame, so that tiles need only short margins.

    The OTF's kink at zero frequency (``1 - OTF ~ |f|``) is what gives the PSF its smooth ``1/r^3`` tail (the
    energy beyond radius R ~ 1/R): a tile window would wrap that tail. Split with a C-infinity low-pass
    ``G`` (1 at f = 0, 0 beyond ``f_split``, cycles per coarse sample): ``OTF = OTF G + OTF (1 - G)``. The
    part ``OTF (1 - G)`` has no kink at zero, so its PSF keeps only the oscillating tail (which averages out
    over an edge) and is formed per tile window; the part ``OTF G`` -- the smooth tail -- is formed here from
    the band ``|f| < f_split`` of the whole frame's DFT, computed exactly in bands of rows (a real FFT of each
    frame row, then an FFT along the columns of the kept band only: memory ``rows x band``), and evaluated
    at each tile's output pixels: where the output grid divides the frame (integer ratios) by folding the band
    onto that grid and inverse FFTs, its rows once and each band of output rows once; else by a matrix DFT
    (whose cost grows with the cube of the scene's side). ``f_split = 22 / margin`` (coarse samples), so the part
    ``G`` removes from the tile lies within half the margin.

    When the whole coarse frame needs no more memory than one tile's window, tiling would save nothing: the
    exact image is then formed at once (:meth:`Simulator.form_image`) and ``image`` holds it; tiles are its
    slices.
    """

    def __init__(self, sim: Simulator, coarse: np.ndarray, *, margin_px: int, band_bytes: float = _FAR_BAND_BYTES):
        import scipy.fft as sfft

        from satchain.engine import spectral

        self.sim, self.image = sim, None
        if sim.frame_bytes <= _window_bytes(sim, margin_px):  # tiles would save no memory: the exact image at once
            self.image = sim.form_image(coarse)
            return
        self.f_split = far_split(sim, margin_px)
        ly, lx = sim.frame_shape
        ey, ex = sim.frame_ext
        by, bx = spectral.band_index(ly, self.f_split), spectral.band_index(lx, self.f_split)
        rows_x = np.empty((ly, bx + 1), dtype=np.complex64)  # the frame's rows, transformed, band only
        h = max(1, int(band_bytes // (4 * lx)))
        for a in range(0, ly, h):
            blk = sim._frame_window(coarse, (a - ey, -ex), (min(h, ly - a), lx))
            rows_x[a : a + blk.shape[0]] = sfft.rfft(blk, axis=1, workers=sim.params.workers)[:, : bx + 1]
        full = sfft.fft(rows_x, axis=0, workers=sim.params.workers, overwrite_x=True)
        my = np.fft.fftfreq(ly, 1.0 / ly).round().astype(np.int64)
        keep = np.abs(my) <= by
        spec = spectral.BandSpectrum(full[keep], my[keep], np.arange(bx + 1), (ly, lx))
        del rows_x, full
        # the band's values, filtered (OTF x G), Hermitian-weighted and normalised: fixed for every tile
        self.values = sim.band_values(spec, weight=self.low) * spec.cx[None, :] / (ly * lx)
        self.my, self.mx = spec.my, spec.mx
        self.origin_px = (-ey * sim.D, -ex * sim.D)  # input pixel of frame sample 0
        self.n_px = (ly * sim.D, lx * sim.D)
        self._rows: tuple[int, int] | None = None
        self._rows_values: np.ndarray | None = None
        self._grid = self._output_grid_rows()

    def _output_grid_rows(self):
        """Where the output grid divides the frame (integer ratios, the frame a whole number of output pixels
        from an output pixel's edge): the band transformed along the rows onto every output row of the frame
        (its rows folded onto the output grid and inverse-transformed: FFTs, not a matrix DFT per band), the
        columns' footprint transfer, the output grid's offset in the frame and its width; else None."""
        import scipy.fft as sfft

        from satchain.engine.spectral import _fold, footprint_transfer

        sim = self.sim
        (ky, kx), (oy, ox), (ny_px, nx_px) = sim.k_int, self.origin_px, self.n_px
        if sim.time_path is not None or not (ky and kx) or ny_px % ky or nx_px % kx or oy % ky or ox % kx:
            return None
        noy = ny_px // ky
        ay = footprint_transfer(self.my, centre=sim.ys.centres(0, 1)[0], width_px=sim.ys.width_px, n_total=ny_px)
        ax = footprint_transfer(self.mx, centre=sim.xs.centres(0, 1)[0], width_px=sim.xs.width_px, n_total=nx_px)
        rows = sfft.ifft(_fold(self.values * ay[:, None], self.my, noy, axis=0), axis=0, overwrite_x=True)
        rows *= noy
        return rows, ax, (-oy // ky, -ox // kx), nx_px // kx

    def low(self, fy: np.ndarray, fx: np.ndarray) -> np.ndarray:
        """``G(fy, fx)``, frequencies in cycles per coarse sample."""
        from satchain.engine.spectral import lowpass

        return lowpass(fy, 0.0, self.f_split) * lowpass(fx, 0.0, self.f_split)

    def high(self, fy: np.ndarray, fx: np.ndarray) -> np.ndarray:
        """``1 - G``: the part formed per tile window."""
        return 1.0 - self.low(fy, fx)

    def tile(self, rows: tuple[int, int], cols: tuple[int, int]) -> np.ndarray:
        """The part ``OTF G`` at output pixels ``rows x cols`` (input units): from the output grid's rows (see
        :meth:`_output_grid_rows`), else a matrix DFT with footprint averaging along each axis (the row
        transform is kept for the next tile of the same rows)."""
        from satchain.engine.spectral import sampling_matrix

        sim = self.sim
        if sim.time_path is not None:  # every row moved along the line of sight of its TDI window
            from satchain.engine.timepath import form_rows

            my = sampling_matrix(sim.ys.centres(*rows) - self.origin_px[0], sim.ys.width_px, 0, self.n_px[0], self.my)
            mx = sampling_matrix(sim.xs.centres(*cols) - self.origin_px[1], sim.xs.width_px, 0, self.n_px[1], self.mx)
            fy, fx = self.my * sim.k[0] / self.n_px[0], self.mx * sim.k[1] / self.n_px[1]
            return form_rows(sim.time_path, rows, my, self.values, mx, fy, fx)
        if self._grid is not None:  # the band of rows on the whole output grid at once, by FFTs
            import scipy.fft as sfft

            from satchain.engine.spectral import _fold

            grid_rows, ax, (dy, dx), nox = self._grid
            if rows != self._rows:  # (the output grid is periodic over the frame)
                band = grid_rows.take(np.arange(rows[0], rows[1]) + dy, axis=0, mode="wrap") * ax[None, :]
                img = sfft.ifft(_fold(band, self.mx, nox, axis=1), axis=1, overwrite_x=True)
                self._rows, self._rows_values = rows, img.real * nox
            assert self._rows_values is not None  # these rows', made above or for the tile before
            return self._rows_values.take(np.arange(cols[0], cols[1]) + dx, axis=1, mode="wrap")
        if rows != self._rows:
            my = sampling_matrix(sim.ys.centres(*rows) - self.origin_px[0], sim.ys.width_px, 0, self.n_px[0], self.my)
            self._rows, self._rows_values = rows, my @ self.values
        mx = sampling_matrix(sim.xs.centres(*cols) - self.origin_px[1], sim.xs.width_px, 0, self.n_px[1], self.mx)
        return np.real(self._rows_values @ mx.T)


def _col_spans(nx: int, t: int) -> list[tuple[int, int]]:
    """The column ranges of the output tiles: ``t`` wide, the last one up to ``1.5 t`` (a remainder narrower than
    ``t / 2`` joins its neighbour rather than paying a whole window for a sliver)."""
    starts = list(range(0, nx, t))
    if len(starts) > 1 and nx - starts[-1] < t // 2:
        starts.pop()
    return [(c0, starts[i + 1] if i + 1 < len(starts) else nx) for i, c0 in enumerate(starts)]


def stream_tiles(
    sim: Simulator,
    coarse: np.ndarray,
    *,
    rows: tuple[int, int] | None = None,
    sensor: SensorModel | None = None,
    units: str = "reflectance",
    noise: bool = False,
    seed: int = 0,
    far: FarField | Literal[False] | None = None,
) -> Iterator[tuple[int, int, np.ndarray]]:
    """Stage 2 (and the sensor) tile by tile, row-major: yields ``(row0, col0, tile)`` for the output rows
    ``rows`` (default all; ``rows[0]`` on the tile grid). Tiles lie on the fixed noise-block grid, so with
    a ``sensor`` the noise is that of :meth:`Simulator.run`. ``far``: the whole frame's long-range part
    (:class:`FarField`, built here when None; ``False``: none, the PSF tail beyond the margin is wrapped)."""
    t, m = stream_tile_px(sim), int(sim.params.stream_margin_px)
    if far is None:
        far = FarField(sim, coarse, margin_px=m)
    ny, nx = sim.output_shape
    r_lo, r_hi = (0, ny) if rows is None else rows
    if r_lo % t:
        raise ConfigError(f"rows = {rows!r}: must start on the tile grid (multiples of {t})")
    for r0 in range(r_lo, min(r_hi, ny), t):
        r1 = min(r0 + t, ny, r_hi)
        for c0, c1 in _col_spans(nx, t):
            # a tile cut by the image's edge is formed as a whole one (its window longer at the far end: more
            # context), so that the tiles' windows share a shape and the OTF (Simulator.band_values)
            full = ((r0, r1), (c0, c1)) if sim.time_path is not None else ((r0, r0 + t), (c0, max(c1, c0 + t)))
            if far and far.image is not None:  # the whole frame at once (FarField: no larger than a window)
                img = far.image[r0:r1, c0:c1].copy()
            else:
                img = sim.form_tile(coarse, *full, margin_px=m, weight=far.high if far else None)[: r1 - r0, : c1 - c0]
                if far:
                    img += far.tile((r0, r1), (c0, c1))
            if sensor is not None:
                img = sensor.convert(
                    img, origin=(r0, c0), units=units, noise=noise, seed=seed, block_px=sim.params.noise_block_px
                )
            yield r0, c0, img


def write_streamed(
    path: str | os.PathLike,
    sim: Simulator,
    coarse: np.ndarray,
    *,
    sensor: SensorModel | None = None,
    units: str = "reflectance",
    noise: bool = False,
    seed: int = 0,
    bit_depth: int | None = None,
    pixel_m: float,
    metadata: dict[str, Any] | None = None,
    preview: bool = True,
    progress: Progress | None = None,
) -> Path | None:
    """Stage 2 + sensor streamed into a tiled (Big)TIFF at ``path`` (atomically), band by band of output
    tiles, with the file type and metadata of :func:`satchain.io.images.write_simulated`; and a PNG preview of a
    strided subsample (at most :data:`PREVIEW_MAX_PX` a side) beside it. Returns the preview path."""
    from satchain.io import images as io
    t = stream_tile_px(sim)
    ny, nx = sim.output_shape
    dtype = io.simulated_dtype(units, bit_depth)
    top = 2.0 ** (12 if bit_depth is None else int(bit_depth)) - 1
    meta = {
        **(metadata or {}),
        "units": units,
        "stage2": "streamed",
        "stream_tile_px": t,
        "stream_margin_px": int(sim.params.stream_margin_px),
    }
    if units == "dn":
        meta["bit_depth"] = 12 if bit_depth is None else int(bit_depth)
    tiff_tile = next(s for s in (256, 128, 64, 32, 16) if t % s == 0)
    stride = max(1, -(-max(ny, nx) // PREVIEW_MAX_PX))
    thumb = np.zeros((-(-ny // stride), -(-nx // stride)), dtype=np.float64)
    n_bands, done = -(-ny // t), [0]
    far = FarField(sim, coarse, margin_px=int(sim.params.stream_margin_px))  # once, for every band

    def tiff_tiles():
        for r0 in range(0, ny, t):
            band = np.zeros((min(t, ny - r0), nx), dtype=dtype)
            for _, c0, img in stream_tiles(
                sim, coarse, rows=(r0, r0 + t), sensor=sensor, units=units, noise=noise, seed=seed, far=far
            ):
                a = np.clip(np.round(img), 0, top) if units == "dn" else img
                band[:, c0 : c0 + img.shape[1]] = a.astype(dtype)
                sub = img[(-r0) % stride :: stride, (-c0) % stride :: stride]
                thumb[-(-r0 // stride) :][: sub.shape[0], -(-c0 // stride) :][:, : sub.shape[1]] = sub
            for rr in range(0, band.shape[0], tiff_tile):
                for cc in range(0, nx, tiff_tile):
                    yield band[rr : rr + tiff_tile, cc : cc + tiff_tile]
            done[0] += 1
            if progress is not None:
                progress(done[0], n_bands)

    io.write_tiff_tiles(
        path, tiff_tiles(), shape=(ny, nx), dtype=dtype, tile=(tiff_tile, tiff_tile), pixel_m=pixel_m, metadata=meta
    )
    if not preview:
        return None
    png = Path(path).with_suffix(".png")
    io.write_png(png, io.preview_uint8(thumb), pixel_m=pixel_m * stride)
    return png


def simulate_to_tiff(
    ground_truth,
    system,
    path: str | os.PathLike,
    *,
    pixel_m: float | None = None,
    params=None,
    sensor: SensorModel | None = None,
    units: str = "reflectance",
    noise: bool = False,
    seed: int = 0,
    scratch_dir: str | os.PathLike | None = None,
    progress: Progress | None = None,
) -> Path:
    """Simulate ``ground_truth`` (an array with ``pixel_m``, a scene or a source) on the streamed path into
    the tiled TIFF ``path`` (and its PNG preview), whatever its size: the coarse grid lives in a scratch
    folder in ``scratch_dir`` (default: beside ``path``) and neither it nor the image is ever held whole.

    Examples
    --------
    >>> import tempfile
    >>> from satchain import io, load_preset
    >>> p = Path(tempfile.mkdtemp()) / "flat.tif"
    >>> _ = simulate_to_tiff(np.full((700, 700), 0.2), load_preset("ankarasat3"), p, pixel_m=0.035)
    >>> img, _ = io.read_image(p)
    >>> img.shape, bool(np.allclose(img, 0.2, atol=1e-6))
    ((50, 50), True)
    """
    from satchain._validate import check_choice
    from satchain.engine.sensor import OUTPUT_UNITS
    from satchain.engine.simulate import SimParams
    from satchain.engine.sources import as_ground_truth

    check_choice("units", units, OUTPUT_UNITS)
    if sensor is None and (noise or units in ("dn", "electrons", "radiance")):
        raise ConfigError(f"units = {units!r}, noise = {noise!r}: need a SensorModel (radiometry) for that")
    src = as_ground_truth(ground_truth, pixel_m=pixel_m)
    sim = Simulator(system, input_pixel_m=src.pixel_m, input_shape=src.shape_px, params=params or SimParams(),
                    motion_seed=seed)  # fmt: skip
    path = Path(path)
    with coarse_store(sim, scratch_dir or path.parent, prefix=f".{path.name}.staging-") as coarse:
        sim.decimate(src, out=coarse, progress=progress)
        write_streamed(
            path,
            sim,
            coarse,
            sensor=sensor,
            units=units,
            noise=noise,
            seed=seed,
            bit_depth=sensor.bit_depth if sensor is not None else None,
            pixel_m=system.gsd_act_m,
            metadata={"system": system.name, "seed": seed, "noise": noise, "input_pixel_m": src.pixel_m},
        )
    return path
