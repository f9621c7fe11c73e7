"""The engine's accuracy and performance knobs (:class:`SimParams`), explicit and frozen: there are no global
settings. Used by :class:`satchain.engine.simulate.Simulator`, which re-exports it.

Examples
--------
>>> SimParams().far_margin_px, SimParams(border="periodic").border
(128, 'periodic')
"""

from __future__ import annotations

from dataclasses import dataclass

from satchain._validate import check_choice, check_range
from satchain.engine.sources import BORDER_RULES
from satchain.errors import ConfigError

__all__ = ["SimParams"]


@dataclass(frozen=True)
class SimParams:
    """Accuracy and performance knobs of the engine (explicit and frozen; there are no global settings).

    Parameters
    ----------
    far_margin_px : int
        Output pixels by which the coarse frame extends beyond the ground truth (by the border rule); the
        PSF tails are exact within the frame.
    exact_border_px : int
        Output pixels beyond the ground truth's edge that stage 1 decimates from the input continued by the
        border rule itself (exact); farther out the coarse frame is continued by the same rule on the coarse
        grid, an approximation that reaches the image only through the PSF's far tails.
    border : {"symmetric", "periodic", "constant"}
        How the ground truth is continued beyond its edge; ``border_value`` for "constant". "periodic" is
        exact when the input size is a multiple of the decimation factor ``Simulator.D``.
    phase_px : (float, float)
        Offset (rows, cols) of the detector grid's origin on the input grid, input pixels, >= 0.
    stopband_ratio : float
        Decimation low-pass stop frequency / optical cutoff (> 1). Larger: shorter tile margins, less
        decimation.
    max_tile_bytes : int
        Memory for one decimation tile; sets the tile size.
    max_frame_bytes : int
        Memory allowed for the coarse frame; larger work is refused up front with the amount it needs.
    noise_block_px : int
        Side of the fixed noise-block grid (output pixels).
    workers : int
        Threads for the FFTs.
    stream_tile_px : int
        Streamed stage 2 (:mod:`satchain.engine.stream`, for inputs whose coarse frame does not fit): output
        tile side, output pixels (rounded up to a multiple of ``noise_block_px`` and of the output period
        that keeps tiles on the coarse grid).
    stream_margin_px : int
        Streamed stage 2: output pixels of coarse frame read beyond each side of a tile; the PSF tail beyond
        it is wrapped around the tile's window instead of taken from the scene (the error it leaves is
        measured in ``benchmarks/bench_stream.py``).
    pass_cy_per_px : float
        Stage 1's pass band, cycles per input pixel, when wider than the optics' cutoff (0: the cutoff). The
        low-pass is then exactly 1 up to this frequency, so its coarse grid serves every system whose cutoff lies
        below it (the bands of one pixel grid share one: :mod:`satchain.engine.bands_shared`); the image is
        unchanged within the kernel's tails (the low-pass is 1 wherever the OTF is not 0). >= 0.
    """

    far_margin_px: int = 128
    exact_border_px: int = 16
    border: str = "symmetric"
    border_value: float = 0.0
    phase_px: tuple[float, float] = (0.0, 0.0)
    stopband_ratio: float = 1.8
    max_tile_bytes: int = 640 * 2**20
    max_frame_bytes: int = 3 * 2**30
    noise_block_px: int = 64
    workers: int = 2
    stream_tile_px: int = 2048
    stream_margin_px: int = 128
    pass_cy_per_px: float = 0.0

    def __post_init__(self) -> None:
        check_choice("border", self.border, BORDER_RULES)
        if not 0 <= int(self.far_margin_px) <= 100_000:
            raise ConfigError(f"far_margin_px = {self.far_margin_px!r}: must be in [0, 100000]")
        if not 0 <= int(self.exact_border_px) <= 100_000:
            raise ConfigError(f"exact_border_px = {self.exact_border_px!r}: must be in [0, 100000]")
        for v in self.phase_px:
            check_range("phase_px", v, 0, None)
        check_range("stopband_ratio", self.stopband_ratio, 1.05, 10)
        check_range("max_tile_bytes", self.max_tile_bytes, 1 << 20, None)
        check_range("max_frame_bytes", self.max_frame_bytes, 1 << 20, None)
        if not 1 <= int(self.noise_block_px) <= 4096:
            raise ConfigError(f"noise_block_px = {self.noise_block_px!r}: must be in [1, 4096]")
        if not 1 <= int(self.workers) <= 256:
            raise ConfigError(f"workers = {self.workers!r}: must be in [1, 256]")
        if not 64 <= int(self.stream_tile_px) <= 65536:
            raise ConfigError(f"stream_tile_px = {self.stream_tile_px!r}: must be in [64, 65536]")
        if not 0 <= int(self.stream_margin_px) <= 100_000:
            raise ConfigError(f"stream_margin_px = {self.stream_margin_px!r}: must be in [0, 100000]")
        check_range("pass_cy_per_px", self.pass_cy_per_px, 0.0, None)
