"""The memory a simulation will need, estimated from its plan before anything is allocated.

The engine bounds its own working set (one decimation tile, the coarse frame: ``SimParams``); what grows
with the job is the coarse grid (4 bytes per coarse sample), the output image and the sensor's temporaries
(about :data:`OUTPUT_BYTES_PER_PX` per output pixel: the folded complex spectrum, the float64 image, noise
draws and the file's copy) and, optionally, the focal-plane image. :func:`check_simulation_memory` refuses a
job whose estimate exceeds :func:`satchain._safety.memory_limit_bytes` with the need in GiB. Where it does not
fit, ``satchain simulate`` takes the streamed path instead when that fits
(:func:`satchain.engine.stream.choose_streamed`, estimate :func:`satchain.engine.stream.stream_bytes`).
"""

from __future__ import annotations

from satchain._safety import check_memory

__all__ = ["OUTPUT_BYTES_PER_PX", "check_simulation_memory", "simulation_bytes"]

#: bytes per output pixel: complex128 fold + float64 image + sensor temporaries (noise, clipping) + file copy
OUTPUT_BYTES_PER_PX = 64


def simulation_bytes(sim, *, focal_plane: str | None = None) -> float:
    """Estimated peak bytes of ``Simulator.decimate`` + ``run`` (+ ``focal_plane(grid=...)`` when given)."""
    from satchain.engine import simulate as _sim

    ny, nx = sim.n_coarse
    fy, fx = sim.frame_shape
    oy, ox = sim.output_shape
    need = 4.0 * ny * nx  # the coarse grid, kept through the run
    need += max(_sim._FRAME_BYTES_PER_PX * fy * fx, min(sim.params.max_tile_bytes, 20.0 * (sim.D * ny) * (sim.D * nx)))
    need += OUTPUT_BYTES_PER_PX * float(oy) * ox
    if focal_plane == "coarse":
        need += 24.0 * ny * nx
    elif focal_plane == "input":
        need += 24.0 * ny * nx * sim.D * sim.D
    return need


def check_simulation_memory(sim, *, focal_plane: str | None = None) -> None:
    """Raise ResourceLimitError (the need in GiB) when the simulation would not fit in memory."""
    oy, ox = sim.output_shape
    iy, ix = sim.input_shape
    check_memory(
        simulation_bytes(sim, focal_plane=focal_plane),
        f"simulating {iy} x {ix} input px into a {oy} x {ox} px image ({oy * ox / 1e9:.2f} Gpx)",
        fix="check --scene-pixel-m (the input's ground pixel size) or crop the input",
    )
