"""A TIFF whose header claims more pixels than it holds (a forged or damaged header), for the io tests."""

from __future__ import annotations

import struct
from pathlib import Path


def forge_size(path: Path, size: int) -> None:
    """Patch a little-endian TIFF's ImageWidth/ImageLength (tags 256, 257) to LONG ``size``."""
    b = bytearray(path.read_bytes())
    ifd = struct.unpack("<I", b[4:8])[0]
    for k in range(struct.unpack("<H", b[ifd : ifd + 2])[0]):
        e = ifd + 2 + 12 * k
        if struct.unpack("<H", b[e : e + 2])[0] in (256, 257):
            b[e + 2 : e + 4], b[e + 8 : e + 12] = struct.pack("<H", 4), struct.pack("<I", size)
    path.write_bytes(bytes(b))
