"""The procedural ground truth the engine benchmarks share (``bench_engine.py --gigapixel``, ``bench_stream.py``):
a scene generated per window, never held.

Run from the benchmarks folder (as ``python benchmarks/bench_*.py`` does: the script's folder is on the path).
"""

from __future__ import annotations

import numpy as np

#: the input's pixel (m): AnkaraSat-3 at 3.5 cm (k = 14)
PIXEL_M = 0.035


class ProceduralScene:
    """A ground truth generated per window (a pure function of pixel position): only a 16 MiB table is held.

    Bar targets by 4096-row band, slanted edges every 2048 px and a 72-sector star every 2048 px, rendered in
    float32 at a few ns per pixel (the sector pattern, periodic over 2048 x 2048 px, from a table built when the
    scene is made), so that a streamed run measures the engine rather than this input. Picklable (the table is
    rebuilt where it is read), so it also runs on process-based Dask workers."""

    PERIOD = 2048

    def __init__(self, n: int, *, pixel_m: float = PIXEL_M):
        self.pixel_m = pixel_m
        self.shape_px = (n, n)
        self._sectors = None
        self.sectors()  # built here, not in the first read

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_sectors": None}

    def sectors(self) -> np.ndarray:
        """``0.1 sign(sin(36 theta))`` about the centre of a ``PERIOD``-px square, float32."""
        if self._sectors is None:
            p = self.PERIOD
            d = np.arange(p, dtype=np.float64) - p / 2
            self._sectors = (0.1 * np.sign(np.sin(36 * np.arctan2(d[:, None], d[None, :])))).astype(np.float32)
        return self._sectors

    def read(self, window) -> np.ndarray:
        from satchain.engine.sources import take

        row0, col0, h, w = window
        p = self.PERIOD
        out = take(self.sectors(), np.arange(row0, row0 + h) % p, np.arange(col0, col0 + w) % p)
        x = np.arange(col0, col0 + w, dtype=np.float64)
        # slanted edges every PERIOD px, 0.2 where (x - 0.12 y) mod PERIOD > PERIOD / 2: for integer x that is
        # a PERIOD-periodic pattern of j = (x - floor(0.12 y)) mod PERIOD (j > PERIOD / 2, or j = 0 when
        # 0.12 y is not an integer), so each row adds a slice of one of two tiled patterns
        j = np.arange(p)
        pats = [
            np.tile(np.float32(0.2) * (j > p // 2) + np.float32(0.2) * (frac & (j == 0)), 2 + w // p)
            for frac in (False, True)
        ]
        stripes, band_of = {}, None
        for r in range(h):
            y = row0 + r
            band = y // 4096
            if band != band_of:  # bar targets: one row of stripes per 4096-row band
                if band not in stripes:
                    stripes[band] = (0.45 + 0.15 * np.sign(np.sin(2 * np.pi * x / (37.0 + band * 3.0)))).astype(
                        np.float32
                    )
                row_add, band_of = stripes[band], band
            s = 0.12 * y
            n = int(np.floor(s))
            a = (col0 - n) % p
            out[r] += row_add + pats[s != n][a : a + w]
        return out
