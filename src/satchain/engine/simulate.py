"""The image chain: ground truth -> optics/motion OTF -> detector footprints -> sensor -> image.

Two stages (see :mod:`satchain.engine.spectral`):

1. **decimate** -- the ground truth is read tile by tile (rendered on the fly for scenes), each tile with a short
   margin, low-passed by a filter that is exactly 1 on the optical band and decimated by ``D`` onto a coarse grid.
   This is the only stage that touches the fine grid; memory is bounded by one tile, and the tiles are independent
   (they run in parallel on Dask, :mod:`satchain.engine.distributed`).
2. **form** -- the coarse frame (extended by ``far_margin_px`` output pixels on every side by the border rule) is
   transformed once; the full system OTF (all components but the detector aperture) and the exact detector footprint
   averaging are applied in frequency and evaluated at the output pixels. The PSF's long tails (the obscured Airy
   pattern's energy beyond radius R falls only as 1/R) are thus never cut at a tile seam.

The result equals a full-frame FFT convolution of the ground truth with the same OTF followed by footprint integration,
within ~1e-6, for every output pixel farther than ``far_margin_px`` from the ground truth's edge. Closer to the edge
the ground truth is continued by the border rule (mirror by default).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from satchain._validate import check_choice, check_range
from satchain.config.system import ImagingSystem
from satchain.engine import spectral
from satchain.engine.params import SimParams
from satchain.engine.sensor import OUTPUT_UNITS, SensorModel
from satchain.engine.sources import BorderedWindow, GroundTruth, as_ground_truth, release_pages, take
from satchain.engine.tiling import AxisSampling, Tile, plan_tiles
from satchain.engine.timepath import TimePath, form_rows, time_path
from satchain.errors import ConfigError, ResourceLimitError
from satchain.tf.budget import SystemOTF

__all__ = ["SimParams", "Simulator", "cutoff_cy_per_px", "decimation_factor", "has_pushbroom_motion", "simulate"]

Progress = Callable[[int, int], None]
Weight = Callable[[np.ndarray, np.ndarray], np.ndarray]
_TILE_BYTES_PER_PX = 20  # a float64 render + row chunks + band spectra (generous: an array source needs ~4)
_FRAME_BYTES_PER_PX = 20  # coarse float32 + complex64 half spectrum + band products


def _int_ratio(k: float) -> int | None:
    r = round(k)
    return int(r) if r >= 1 and abs(k - r) <= 1e-9 * k else None


class Simulator:
    """Image formation of ``system`` from a ground truth of ``input_shape`` pixels of ``input_pixel_m``.

    A system with pushbroom motion in time (:func:`has_pushbroom_motion`) forms its rows along the line of sight
    of each instant of their TDI window (:mod:`satchain.engine.timepath`); ``motion_seed`` draws its jitter.

    Examples
    --------
    >>> from satchain import load_preset
    >>> sim = Simulator(load_preset("ankarasat3"), input_pixel_m=0.035, input_shape=(1400, 1400))
    >>> sim.output_shape, sim.D, round(sim.k[0], 6)
    ((100, 100), 4, 14.0)
    """

    def __init__(
        self,
        system: ImagingSystem,
        *,
        input_pixel_m: float,
        input_shape: tuple[int, int],
        params: SimParams = SimParams(),  # noqa: B008
        otf: SystemOTF | None = None,
        motion_seed: int = 0,
    ):
        a = check_range("input_pixel_m", input_pixel_m, 0, None, lo_open=True)
        self.system, self.params, self.input_pixel_m = system, params, a
        self.input_shape = (int(input_shape[0]), int(input_shape[1]))
        det = system.detector
        ny, nx = self.input_shape
        self.ys = AxisSampling(system.gsd_alt_m / a, det.active_width_y_m / det.pitch_y_m, params.phase_px[0], ny)
        self.xs = AxisSampling(system.gsd_act_m / a, det.active_width_x_m / det.pitch_x_m, params.phase_px[1], nx)
        if self.ys.n_output < 1 or self.xs.n_output < 1:
            raise ConfigError(
                f"input_shape = {self.input_shape!r} at input_pixel_m = {a!r}: smaller than one detector pixel "
                f"({system.gsd_alt_m:.4g} x {system.gsd_act_m:.4g} m)"
            )
        self.otf = SystemOTF(system) if otf is None else otf
        self.time_path: TimePath | None = None  # pushbroom motion in time (set_time_path)
        self._transfer: dict[tuple, np.ndarray] = {}  # band_values' transfer
        self._exclude: tuple[str, ...] = ("detector",)
        # focal-plane cy/mm per cycle per input pixel, along y (ALT) and x (ACT): differ off nadir
        self.to_cy_per_mm = tuple(system.focal_cy_per_mm_per_ground_cy_per_m(ax) / a for ax in ("alt", "act"))
        self.f_cut = cutoff_cy_per_px(system, self.otf, a)  # cycles per input pixel, the wider axis
        from satchain.engine.yaw import yaw_rotation_deg

        self.yaw_deg = yaw_rotation_deg(system)  # the detector turned: the ground truth rotated (engine.yaw)
        self._yaw_cache: tuple[np.ndarray, np.ndarray] | None = None
        self.yaw_store: Callable[[tuple[int, int]], np.ndarray] | None = None  # set by engine.stream.coarse_store
        self._plan_decimation()
        self._plan_frame()
        if has_pushbroom_motion(system):  # rows formed in time along the line of sight (engine.timepath)
            self.set_time_path(time_path(system, self.output_shape[0], seed=motion_seed))

    def set_time_path(self, path) -> None:
        """Form the image in time along ``path`` (:func:`satchain.engine.timepath.time_path`): every row at the
        line of sight of each instant of its TDI window; the exposure-averaged OTF terms of that motion are then
        left out of the static OTF (the path applies them, with their geometry). None: the static image."""
        self.time_path = path
        names = () if path is None else tuple(n for n in self.otf.component_names if _is_pushbroom(n))
        self._exclude = ("detector", *names)

    # ------------------------------------------------------------------ planning
    def _plan_decimation(self) -> None:
        p = self.params
        self.f_pass = max(self.f_cut, float(p.pass_cy_per_px))  # stage 1's pass band (cycles per input pixel)
        f_stop = p.stopband_ratio * self.f_pass
        self.D = decimation_factor(self.f_pass, p.stopband_ratio)
        # use all the room decimation leaves: the wider the transition, the shorter the low-pass kernel
        self.f_stop = 0.5 / self.D * (1 - 1e-3) if self.D > 1 else f_stop
        if self.D == 1:
            self.margin_fine = 0
        else:
            m = spectral.LOWPASS_SUPPORT / (self.f_stop - self.f_pass)
            self.margin_fine = int(math.ceil(m / self.D)) * self.D
        periodic = p.border == "periodic"
        self.coarse_ext = tuple(
            0 if periodic else int(math.ceil(min(p.exact_border_px, p.far_margin_px) * kk / self.D))
            for kk in (self.ys.k, self.xs.k)
        )
        ny, nx = (-(-n // self.D) + 2 * e for n, e in zip(self.input_shape, self.coarse_ext, strict=True))
        self.n_coarse = (ny, nx)
        side = math.sqrt(p.max_tile_bytes / _TILE_BYTES_PER_PX) - 2 * self.margin_fine
        tile_coarse = int(side // self.D)
        if tile_coarse < 16:
            raise ResourceLimitError(
                f"input_pixel_m = {self.input_pixel_m:g}: far finer than the system resolves (a decimation tile with "
                f"its {self.margin_fine}-px margins needs at least "
                f"{_TILE_BYTES_PER_PX * (16 * self.D + 2 * self.margin_fine) ** 2 / 2**20:.0f} MiB, max_tile_bytes "
                f"allows {p.max_tile_bytes / 2**20:.0f} MiB); use a coarser ground-truth pixel"
            )
        self.tile_coarse = min(tile_coarse, max(self.n_coarse))
        origin, mf = (-self.coarse_ext[0] * self.D, -self.coarse_ext[1] * self.D), self.margin_fine
        self.tiles: list[Tile] = plan_tiles(  # fast: input windows of fast FFT lengths
            self.n_coarse, D=self.D, tile_coarse=self.tile_coarse, margin_px=mf, origin_px=origin, fast=True
        )

    def _plan_frame(self) -> None:
        """Coarse frame: the coarse scene plus an extension on each side; with an integer ratio k the frame
        is a whole number of output pixels and its first output pixel sits on the scene's grid."""
        from satchain.engine.yaw import yaw_margin

        D, p = self.D, self.params
        self.k_int = (_int_ratio(self.ys.k), _int_ratio(self.xs.k))
        ext, length = [], []
        if p.border == "periodic" and self.yaw_deg:
            raise ConfigError(
                "border = 'periodic' with orbit.yaw_steering: a rotated scene is not periodic on its grid; use "
                "'symmetric' or 'constant'"
            )
        if p.border == "periodic":  # the coarse scene is itself the period: no extension
            self.frame_ext, self.frame_shape = (0, 0), self.n_coarse
            ky, kx = (
                ki if ki and (nc * D) % ki == 0 else None for ki, nc in zip(self.k_int, self.n_coarse, strict=True)
            )
            self.k_int = (ky, kx)
            return
        for ax, (kk, ki, nc) in enumerate(zip(self.k, self.k_int, self.n_coarse, strict=True)):
            nc -= 2 * self.coarse_ext[ax]  # the ground truth's own coarse samples
            e = int(math.ceil(p.far_margin_px * kk / D)) + yaw_margin(self.n_coarse, self.yaw_deg)
            q = ki // math.gcd(ki, D) if ki else 1  # coarse samples per aligned output period
            e = -(-e // q) * q
            n = q * spectral_len(-(-(nc + 2 * e) // q))  # a multiple of q with a fast cofactor
            ext.append(e)
            length.append(n)
        self.frame_ext, self.frame_shape = (ext[0], ext[1]), (length[0], length[1])

    @property
    def frame_bytes(self) -> float:
        """Working memory of the full-frame stage 2 (:meth:`form_image`), bytes."""
        return float(_FRAME_BYTES_PER_PX) * self.frame_shape[0] * self.frame_shape[1]

    def check_frame(self) -> None:
        """Refuse the full-frame stage 2 when its frame exceeds ``SimParams.max_frame_bytes``."""
        need, p = self.frame_bytes, self.params
        if need > p.max_frame_bytes:
            ly, lx = self.frame_shape
            raise ResourceLimitError(
                f"input {self.input_shape[0]} x {self.input_shape[1]} px: its coarse frame {ly} x {lx} needs about "
                f"{need / 2**30:.2f} GiB; SimParams.max_frame_bytes allows {p.max_frame_bytes / 2**30:.2f} GiB: use "
                "the streamed stage 2 (satchain.engine.stream), crop the input or raise SimParams.max_frame_bytes"
            )

    @property
    def k(self) -> tuple[float, float]:
        """Output pixel pitch in input pixels, (ALT, ACT)."""
        return self.ys.k, self.xs.k

    @property
    def output_shape(self) -> tuple[int, int]:
        return self.ys.n_output, self.xs.n_output

    # ------------------------------------------------------------------ stage 1
    def decimate_tile(self, source: GroundTruth, tile: Tile) -> np.ndarray:
        """The coarse samples of one tile (its margins read through the border rule)."""
        p = self.params  # the tile is assembled chunk by chunk as it is transformed; NaN/inf shows in the result
        data = BorderedWindow(source, tile.input, rule=p.border, value=p.border_value, dtype=np.float32, check=False)
        out = spectral.decimate_tile(data, D=self.D, f_pass=self.f_pass, f_stop=self.f_stop, workers=p.workers)
        m = self.margin_fine // self.D
        return data.require_finite(out)[m : m + tile.coarse.height, m : m + tile.coarse.width]

    def decimate(
        self, source: GroundTruth, *, progress: Progress | None = None, out: np.ndarray | None = None
    ) -> np.ndarray:
        """Stage 1 over all tiles: the coarse grid of the whole ground truth (float32), written into ``out``
        (e.g. a disk-backed array, :func:`satchain.engine.stream.coarse_store`) when given."""
        if out is not None and (out.shape != self.n_coarse or out.dtype != np.float32):
            raise ConfigError(f"out: shape {out.shape}, dtype {out.dtype} must be {self.n_coarse}, float32")
        coarse = np.empty(self.n_coarse, dtype=np.float32) if out is None else out
        for n, tile in enumerate(self.tiles):
            coarse[tile.coarse.rows, tile.coarse.cols] = self.decimate_tile(source, tile)
            release_pages(coarse)
            if progress is not None:
                progress(n + 1, len(self.tiles))
        return coarse

    # ------------------------------------------------------------------ stage 2
    def form_image(self, coarse: np.ndarray | None, *, spectrum: spectral.BandSpectrum | None = None) -> np.ndarray:
        """Stage 2: OTF, detector footprints and sampling, from the coarse grid to the output image (input
        units, no noise), on the whole coarse frame at once (exact; see :meth:`form_tile` for a window).
        ``spectrum``: the coarse frame's band already transformed (:meth:`frame_spectrum`, at least this system's
        band), e.g. one transform shared by systems that differ only in their OTF; ``coarse`` is then unused."""
        if spectrum is not None:
            spectrum = self.own_band(spectrum)
        elif coarse is not None:
            spectrum = self.frame_spectrum(coarse)
        else:
            raise ConfigError("form_image: give coarse or spectrum")
        (ey, ex) = self.frame_ext
        return self.form_spectrum(spectrum, (-ey, -ex), (0, self.output_shape[0]), (0, self.output_shape[1]))

    def frame_spectrum(self, coarse: np.ndarray, *, f_band: float | None = None) -> spectral.BandSpectrum:
        """The band of the whole coarse frame's DFT (:meth:`form_image`'s transform) up to ``f_band`` cycles per
        input pixel (default the optics' cutoff; up to the coarse grid's Nyquist)."""
        if coarse.shape != self.n_coarse:
            raise ConfigError(f"coarse: shape {coarse.shape} must be {self.n_coarse}")
        self.check_frame()
        (ey, ex) = self.frame_ext
        frame = self._frame_window(coarse, (-ey, -ex), self.frame_shape)
        self._yaw_cache = None  # the rotated frame is not kept beyond this call (its copy is ``frame``)
        return self._block_spectrum(frame, self.f_cut if f_band is None else max(float(f_band), self.f_cut))

    def _block_spectrum(self, block: np.ndarray, f_band: float) -> spectral.BandSpectrum:
        """The band ``|f| <= f_band`` (cycles per input pixel) of a coarse block's DFT."""
        f = f_band * self.D  # cycles per coarse sample
        ly, lx = block.shape
        return spectral.tile_band_spectrum(
            block, by=spectral.band_index(ly, f), bx=spectral.band_index(lx, f), workers=self.params.workers
        )

    def own_band(self, spec: spectral.BandSpectrum) -> spectral.BandSpectrum:
        """``spec`` (a :meth:`frame_spectrum` of this frame, of at least this system's band) restricted to the
        optics' band: exactly the spectrum :meth:`frame_spectrum` gives."""
        ly, lx = self.frame_shape
        if tuple(spec.shape) != (ly, lx):
            raise ConfigError(f"spectrum: frame {tuple(spec.shape)} must be {self.frame_shape}")
        f = self.f_cut * self.D
        return spec.restrict(by=spectral.band_index(ly, f), bx=spectral.band_index(lx, f))

    def frame_map(self, axis: int) -> np.ndarray:
        """Coarse-grid index of every sample of the coarse frame along ``axis`` (frame sample 0 is the
        ground truth's coarse sample ``-frame_ext``); -1 where the frame holds ``border_value``. Under the
        mirror rule: the exact border band from stage 1, then the ground truth's coarse samples mirrored
        about its edges (exact at an edge whose length is a multiple of D: the samples sit at block centres)."""
        from satchain.engine.sources import _map_indices

        e, c, n_all, length = self.frame_ext[axis], self.coarse_ext[axis], self.n_coarse[axis], self.frame_shape[axis]
        if self.params.border == "periodic":
            return np.arange(n_all)
        nc = n_all - 2 * c  # the ground truth's own samples
        t = np.arange(-e, length - e)
        inside = (t >= -c) & (t < nc + c)
        if self.params.border == "constant":
            return np.where(inside, t + c, -1)
        return np.where(inside, t, _map_indices(-e, length, nc, "symmetric")) + c

    def _frame_window(
        self, coarse: np.ndarray, start: tuple[int, int], shape: tuple[int, int], *, rotated: bool = True
    ) -> np.ndarray:
        """Samples ``start .. start + shape`` (ground-truth coarse coordinates) of the coarse frame, taken
        periodically over the frame (as its FFT sees it), as float32; under yaw steering those of the rotated
        frame (:meth:`yaw_frame`) unless ``rotated`` is False."""
        if self.yaw_deg and rotated:
            from satchain.engine.yaw import rotated_window

            return rotated_window(self, coarse, start, shape)
        idx = []
        for ax in (0, 1):
            fm = self.frame_map(ax)
            t = np.arange(start[ax], start[ax] + shape[ax]) + self.frame_ext[ax]
            idx.append(fm[np.mod(t, fm.size)])
        iy, ix = idx
        # only the window's elements are read (a disk-backed coarse grid is never loaded whole)
        out = take(coarse, np.maximum(iy, 0), np.maximum(ix, 0))
        release_pages(coarse)
        if self.params.border == "constant":
            out[iy < 0, :] = self.params.border_value
            out[:, ix < 0] = self.params.border_value
        return out

    def tile_window(self, rows: tuple[int, int], cols: tuple[int, int], margin_px: int) -> tuple[tuple, tuple]:
        """``(start, shape)`` in ground-truth coarse coordinates of the coarse window that :meth:`form_tile`
        transforms for output pixels ``rows x cols`` with ``margin_px`` output pixels of context on each side:
        its start on the output grid's period and its length a fast FFT size (a multiple of that period)."""
        start, shape = [], []
        for ax, (lo, hi) in enumerate((rows, cols)):
            kk, ki, D = self.k[ax], self.k_int[ax], self.D
            q = ki // math.gcd(ki, D) if ki else 1  # coarse samples per aligned output period
            a = int(math.floor((lo - margin_px) * kk / D / q + 1e-9)) * q  # not one period early by rounding
            b = int(math.ceil((hi + margin_px) * kk / D - 1e-9))
            start.append(a)
            shape.append(q * spectral_len(-(-(b - a) // q)))
        return tuple(start), tuple(shape)

    def form_tile(
        self,
        coarse: np.ndarray,
        rows: tuple[int, int],
        cols: tuple[int, int],
        *,
        margin_px: int,
        weight: Weight | None = None,
    ) -> np.ndarray:
        """Stage 2 on a window: output pixels ``rows[0]:rows[1] x cols[0]:cols[1]`` from the coarse frame's
        window extending ``margin_px`` output pixels beyond them (periodic over that window: the PSF's tail
        beyond the margin is wrapped, not cut; it equals :meth:`form_image` as the margin grows). Memory is one
        window; ``coarse`` may be a disk-backed array. ``weight(fy, fx)``: a spectral weight (cycles per coarse
        sample) applied with the OTF, e.g. the near-field part of :mod:`satchain.engine.stream`."""
        if coarse.shape != self.n_coarse:
            raise ConfigError(f"coarse: shape {coarse.shape} must be {self.n_coarse}")
        start, shape = self.tile_window(rows, cols, margin_px)
        if all(n >= f for n, f in zip(shape, self.frame_shape, strict=True)):  # the whole frame is no larger
            (ey, ex), shape = self.frame_ext, self.frame_shape
            start = (-ey, -ex)
        block = self._frame_window(coarse, start, shape)
        return self._form_block(block, start, rows, cols, weight=weight)

    def _form_block(
        self,
        block: np.ndarray,
        start: tuple[int, int],
        rows: tuple[int, int],
        cols: tuple[int, int],
        *,
        weight: Weight | None = None,
    ) -> np.ndarray:
        """Output pixels ``rows x cols`` of the periodic extension of ``block``, whose sample 0 is the ground
        truth's coarse sample ``start``: OTF, footprints and sampling in frequency."""
        spec = self._block_spectrum(block, self.f_cut)
        del block
        return self.form_spectrum(spec, start, rows, cols, weight=weight)

    def yaw_frame(self, coarse: np.ndarray) -> np.ndarray:
        """The coarse frame of ``coarse`` rotated for yaw steering (:func:`satchain.engine.yaw.rotated_frame`)."""
        from satchain.engine.yaw import rotated_frame

        return rotated_frame(self, coarse)

    def band_values(self, spec: spectral.BandSpectrum, *, weight: Weight | None = None) -> np.ndarray:
        """``spec``'s values times the system OTF (without the detector), ``weight(fy, fx)`` (cycles per coarse
        sample) when given, and the phase that puts coarse sample j at input pixel ``D j + (D - 1) / 2``. That
        transfer is kept for the latest bands (up to 64 MiB): the streamed path's tiles share it."""
        key = (spec.shape, spec.my.tobytes(), spec.mx.size, weight, self._exclude, id(self.otf))
        t = self._transfer.get(key)
        if t is None:
            (ly, lx), c = spec.shape, (self.D - 1) / 2.0  # coarse sample j sits at input pixel D j + c
            ny_f, nx_f = ly * self.D, lx * self.D  # block length in input pixels
            fy, fx = spec.my / ny_f * self.to_cy_per_mm[0], spec.mx / nx_f * self.to_cy_per_mm[1]
            t = self.otf(fx[None, :], fy[:, None], exclude=self._exclude)
            if weight is not None:
                t = t * weight(spec.my[:, None] / ly, spec.mx[None, :] / lx)
            t = t * np.exp(-2j * np.pi * spec.my * c / ny_f)[:, None]
            t *= np.exp(-2j * np.pi * spec.mx * c / nx_f)[None, :]
            old = list(self._transfer.items())[-3:]  # the latest 4 bands (the streamed tiles' shapes), <= 64 MiB
            while old and sum(v.nbytes for _, v in old) + t.nbytes > 2**26:
                old.pop(0)
            self._transfer = dict([*old, (key, t)]) if t.nbytes <= 2**26 else {}
        return spec.values * t

    def form_spectrum(
        self,
        spec: spectral.BandSpectrum,
        start: tuple[int, int],
        rows: tuple[int, int],
        cols: tuple[int, int],
        *,
        weight: Weight | None = None,
        fold: bool = True,
    ) -> np.ndarray:
        """Output pixels ``rows x cols`` from the band ``spec`` of the DFT of a periodic coarse block
        (``spec.shape``) whose sample 0 is the ground truth's coarse sample ``start``, its values multiplied by
        ``weight(fy, fx)`` (cycles per coarse sample) when given. ``fold=False``: always the matrix DFT."""
        D = self.D
        ly, lx = spec.shape
        ny_f, nx_f = ly * D, lx * D  # block length in input pixels
        vals = self.band_values(spec, weight=weight)
        scale = 1.0 / (ly * lx)
        ky, kx = self.k_int
        if self.time_path is not None:
            return self._form_moving(vals, spec, start, rows, cols) * scale
        if fold and ky and kx and not ((start[0] * D) % ky or (start[1] * D) % kx or ny_f % ky or nx_f % kx):
            ay = spectral.footprint_transfer(
                spec.my, centre=self.ys.centres(0, 1)[0], width_px=self.ys.width_px, n_total=ny_f
            )
            ax = spectral.footprint_transfer(
                spec.mx, centre=self.xs.centres(0, 1)[0], width_px=self.xs.width_px, n_total=nx_f
            )
            n_out = (ny_f // ky, nx_f // kx)
            vals = vals * ay[:, None]
            vals *= ax[None, :]  # (in place: one temporary less, the same products)
            img = spectral.fold_onto_grid(vals, spec.my, spec.mx, spec.cx, n_out) * scale
            oy, ox = rows[0] - (start[0] * D) // ky, cols[0] - (start[1] * D) // kx
            return img[oy : oy + rows[1] - rows[0], ox : ox + cols[1] - cols[0]]
        my = spectral.sampling_matrix(self.ys.centres(*rows) - start[0] * D, self.ys.width_px, 0, ny_f, spec.my)
        mx = spectral.sampling_matrix(self.xs.centres(*cols) - start[1] * D, self.xs.width_px, 0, nx_f, spec.mx)
        v = vals * spec.cx[None, :]
        (ty, by), (tx, bx) = my.shape, mx.shape
        if ty * by * bx + ty * bx * tx < by * bx * tx + ty * by * tx:  # the cheaper order of the two products
            return np.real((my @ v) @ mx.T) * scale
        return np.real(my @ (v @ mx.T)) * scale

    def _form_moving(self, vals, spec, start, rows, cols) -> np.ndarray:
        """:meth:`form_spectrum`'s matrix evaluation with every row moved along the time path (unscaled)."""

        D = self.D
        ny_f, nx_f = spec.shape[0] * D, spec.shape[1] * D
        my = spectral.sampling_matrix(self.ys.centres(*rows) - start[0] * D, self.ys.width_px, 0, ny_f, spec.my)
        mx = spectral.sampling_matrix(self.xs.centres(*cols) - start[1] * D, self.xs.width_px, 0, nx_f, spec.mx)
        fy, fx = spec.my * self.k[0] / ny_f, spec.mx * self.k[1] / nx_f  # cycles per detector pixel
        assert self.time_path is not None  # form_spectrum calls this only along a time path
        return form_rows(self.time_path, rows, my, vals * spec.cx[None, :], mx, fy, fx)

    def focal_plane(self, coarse: np.ndarray, *, grid: str = "input") -> np.ndarray:
        """The focal-plane irradiance image (the paper's Figure 4b, in input units): the ground truth filtered
        by the system OTF without the detector aperture (under yaw steering the ground turned, as the image sees it).

        ``grid="input"``: on the input grid, pixel (i, j) at input pixel (i, j) -- exact, because the image is
        band-limited below the coarse grid's Nyquist frequency, so zero-padding its spectrum interpolates it
        without error. ``grid="coarse"``: the same image sampled at the centre of every ``D x D`` input block
        (sample (j, i) at input pixel (D j + (D-1)/2, D i + (D-1)/2)), ``D**2`` times smaller. Periodic over
        the coarse grid (the mirror band beyond the edges included)."""
        import scipy.fft as sfft

        check_choice("grid", grid, ("input", "coarse"))
        D, w = self.D, self.params.workers
        (ny, nx), (cy, cx) = coarse.shape, self.coarse_ext  # under a yaw: the frame turned as the image's (engine.yaw)
        f = sfft.rfft2(self._frame_window(coarse, (-cy, -cx), (ny, nx)) if self.yaw_deg else coarse, workers=w)
        fy = np.fft.fftfreq(ny)[:, None] / D  # cycles per input pixel
        fx = np.fft.rfftfreq(nx)[None, :] / D
        f *= self.otf(fx * self.to_cy_per_mm[1], fy * self.to_cy_per_mm[0], exclude=("detector",))
        if grid == "coarse" or D == 1:
            out = sfft.irfft2(f, s=(ny, nx), workers=w)
            return out[cy : ny - cy, cx : nx - cx]
        need = 16 * ny * nx * D * D
        if need > self.params.max_frame_bytes:
            raise ResourceLimitError(
                f"focal plane on the input grid needs about {need / 2**30:.2f} GiB; SimParams.max_frame_bytes "
                f"allows {self.params.max_frame_bytes / 2**30:.2f} GiB: use grid='coarse'"
            )
        c = (D - 1) / 2.0  # coarse samples sit at block centres: shift so that sample n is input pixel n
        f *= np.exp(-2j * np.pi * fy * c) * np.exp(-2j * np.pi * fx * c)
        big = np.zeros((ny * D, nx * D // 2 + 1), dtype=np.complex128)
        rows = np.mod(np.fft.fftfreq(ny, 1.0 / ny).round().astype(np.int64), ny * D)
        big[rows, : nx // 2 + 1] = f
        out = sfft.irfft2(big, s=(ny * D, nx * D), workers=w) * (D * D)
        r0, c0 = cy * D, cx * D
        return out[r0 : r0 + self.input_shape[0], c0 : c0 + self.input_shape[1]]

    def run(
        self,
        source: GroundTruth,
        *,
        sensor: SensorModel | None = None,
        units: str = "reflectance",
        noise: bool = False,
        seed: int = 0,
        progress: Progress | None = None,
        coarse: np.ndarray | None = None,
        spectrum: spectral.BandSpectrum | None = None,
    ) -> np.ndarray:
        """Both stages and the sensor: the simulated image in ``units``. ``coarse``: a stage-1 result
        already computed by :meth:`decimate` (e.g. to also form :meth:`focal_plane` from it); ``spectrum``: its
        frame's transform already computed (:meth:`form_image`)."""
        check_choice("units", units, OUTPUT_UNITS)
        if sensor is None and (noise or units in ("dn", "electrons", "radiance")):
            raise ConfigError(f"units = {units!r}, noise = {noise!r}: need a SensorModel (radiometry) for that")
        if tuple(source.shape_px) != self.input_shape:
            raise ConfigError(f"source shape {tuple(source.shape_px)} differs from the planned {self.input_shape}")
        self.check_frame()  # before stage 1, not after it
        if spectrum is not None:
            img = self.form_image(None, spectrum=spectrum)
        else:
            img = self.form_image(self.decimate(source, progress=progress) if coarse is None else coarse)
        if sensor is not None:
            img = sensor.convert(
                img, origin=(0, 0), units=units, noise=noise, seed=seed, block_px=self.params.noise_block_px
            )
        return img


def decimation_factor(f_pass: float, stopband_ratio: float) -> int:
    """Stage 1's decimation ``D`` for a pass band ``f_pass`` (cycles per input pixel): the largest whose coarse
    grid's Nyquist ``1 / (2 D)`` leaves the stop band at least ``stopband_ratio`` times the pass band (1 when none
    does).

    Examples
    --------
    >>> decimation_factor(0.133, 1.8), decimation_factor(0.188, 1.8), decimation_factor(0.188, 1.25)
    (2, 1, 2)
    """
    f_stop = stopband_ratio * f_pass
    return max(1, int(math.floor(0.5 / f_stop - 1e-9))) if f_stop < 0.25 else 1


def cutoff_cy_per_px(system: ImagingSystem, otf: SystemOTF, input_pixel_m: float) -> float:
    """The optics' cutoff of ``otf`` (``system``'s) in cycles per input pixel of ``input_pixel_m``, along the axis
    where it is widest (:attr:`Simulator.f_cut`)."""
    to = (system.focal_cy_per_mm_per_ground_cy_per_m(ax) / input_pixel_m for ax in ("alt", "act"))
    return float(otf.cutoff_cy_per_mm / min(to))


def has_pushbroom_motion(system: ImagingSystem) -> bool:
    """Whether ``system`` has line-of-sight motion in time (``[[motion.oscillation]]``, ``[motion.jitter_psd]``,
    ``[motion.line_of_sight]``, ``motion.line_rate_error``, ``orbit.earth_rotation``): its image is then formed
    in time."""
    m = system.motion
    return bool(m.time_varying or m.line_rate_error or system.orbit.earth_rotation)


def _is_pushbroom(name: str) -> bool:
    """The OTF components of pushbroom motion (:class:`satchain.tf.pushbroom.PushbroomTerms`)."""
    return name.startswith(("oscillation_", "jitter_psd_", "los_log_")) or name == "tdi_drift"


def spectral_len(n: int) -> int:
    """The next 5-smooth length >= n (fast for FFTs)."""
    import scipy.fft as sfft

    return sfft.next_fast_len(n, real=True)


def simulate(
    ground_truth,
    system: ImagingSystem,
    *,
    pixel_m: float | None = None,
    params: SimParams = SimParams(),  # noqa: B008
    sensor: SensorModel | None = None,
    units: str = "reflectance",
    noise: bool = False,
    seed: int = 0,
    progress: Progress | None = None,
    input_scale: float | None = None,
) -> np.ndarray:
    """The image of ``ground_truth``: an array with ``pixel_m`` (no NaN/mask; ints as simulate_image), scene or source.

    Examples
    --------
    >>> from satchain import load_preset
    >>> img = simulate(np.full((700, 700), 0.2), load_preset("ankarasat3"), pixel_m=0.035)
    >>> img.shape, bool(np.allclose(img, 0.2, atol=1e-6))
    ((50, 50), True)
    """
    src = as_ground_truth(ground_truth, pixel_m=pixel_m, input_scale=input_scale)
    sim = Simulator(system, input_pixel_m=src.pixel_m, input_shape=src.shape_px, params=params, motion_seed=seed)
    return sim.run(src, sensor=sensor, units=units, noise=noise, seed=seed, progress=progress)
