"""Image I/O round trips, pixel-size metadata, atomic writes and errors."""

from __future__ import annotations

import os

import numpy as np
import pytest
import tifffile

from satchain.errors import InputError, SatchainIOError
from satchain.io.images import atomic_path, read_image, write_npy, write_png, write_tiff, write_tiff_tiles


@pytest.mark.parametrize("dtype", [np.float32, np.uint16])
def test_tiff_round_trip_with_pixel_size(tmp_path, dtype):
    rng = np.random.default_rng(1)
    a = (rng.random((70, 45)) * 1000).astype(dtype)
    write_tiff(tmp_path / "a.tif", a, pixel_m=0.035, origin_m=(1.5, 2.5), tile=(32, 32))
    b, meta = read_image(tmp_path / "a.tif")
    assert b.dtype == dtype
    np.testing.assert_array_equal(a, b)
    assert meta["pixel_m"] == 0.035 and meta["origin_m"] == pytest.approx([1.5, 2.5])
    with tifffile.TiffFile(tmp_path / "a.tif") as tf:
        tags = tf.pages[0].tags
        assert tuple(tags[33550].value) == (0.035, 0.035, 0.0)  # GeoTIFF ModelPixelScaleTag
        assert tuple(tags[33922].value) == (0.0, 0.0, 0.0, 1.5, -2.5, 0.0)  # ModelTiepointTag, y up
        assert tf.pages[0].is_tiled and not tf.is_bigtiff


def test_geotiff_scale_tag_alone_gives_pixel_size(tmp_path):
    """A GeoTIFF written by another tool (only the GeoTIFF tags, no satchain description)."""
    tags = [(33550, "d", 3, (0.5, 0.5, 0.0), True), (33922, "d", 6, (0, 0, 0, 100.0, 200.0, 0), True)]
    tifffile.imwrite(tmp_path / "g.tif", np.zeros((4, 4), np.uint8), extratags=tags, metadata=None)
    _, meta = read_image(tmp_path / "g.tif")
    assert meta["pixel_m"] == 0.5 and meta["origin_m"] == [100.0, -200.0]


def test_bigtiff_forced_and_tiles_streamed(tmp_path):
    def tiles():
        for r in range(3):
            for c in range(2):
                yield np.full((16, 16) if c == 0 else (16, 4), r * 10 + c, np.float32)

    write_tiff_tiles(tmp_path / "b.tif", tiles(), shape=(48, 20), dtype=np.float32, tile=(16, 16), bigtiff=True)
    b, meta = read_image(tmp_path / "b.tif")
    assert meta["bigtiff"] is True and b.shape == (48, 20)
    assert b[17, 0] == 10 and b[47, 19] == 21 and "pixel_m" not in meta


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_png_round_trip(tmp_path, dtype):
    a = np.random.default_rng(2).integers(0, np.iinfo(dtype).max, (13, 17), endpoint=True).astype(dtype)
    write_png(tmp_path / "a.png", a, pixel_m=0.49)
    b, meta = read_image(tmp_path / "a.png")
    assert b.dtype == dtype
    np.testing.assert_array_equal(a, b)
    assert meta["pixel_m"] == 0.49


def test_npy_round_trip(tmp_path):
    a = np.arange(12.0).reshape(3, 4)
    write_npy(tmp_path / "a.npy", a)
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "a.npy").stat().st_mode & 0o777 == 0o666 & ~umask  # not mkstemp's 0600
    b, meta = read_image(tmp_path / "a.npy")
    np.testing.assert_array_equal(a, b)
    assert "pixel_m" not in meta


def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    with pytest.raises(ValueError, match="fail"):
        with atomic_path(tmp_path / "x.txt") as tmp:
            tmp.write_text("partial")
            raise ValueError("fail")
    assert list(tmp_path.iterdir()) == []

    def bad_tiles():
        yield np.zeros((16, 16), np.float32)
        raise RuntimeError("renderer died")

    with pytest.raises(RuntimeError, match="renderer died"):
        write_tiff_tiles(tmp_path / "t.tif", bad_tiles(), shape=(32, 32), dtype=np.float32, tile=(16, 16))
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_replaces_existing_only_on_success(tmp_path):
    target = tmp_path / "a.npy"
    write_npy(target, np.zeros(3))
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_bytes(b"junk")
            raise RuntimeError
    np.testing.assert_array_equal(read_image(target)[0], np.zeros(3))


def test_io_errors(tmp_path):
    with pytest.raises(SatchainIOError, match="no such file"):
        read_image(tmp_path / "missing.tif")
    (tmp_path / "a.bmp").write_bytes(b"BM")
    with pytest.raises(SatchainIOError, match="unsupported suffix"):
        read_image(tmp_path / "a.bmp")
    (tmp_path / "c.tif").write_bytes(b"not a tiff at all")
    with pytest.raises(SatchainIOError, match="cannot read"):
        read_image(tmp_path / "c.tif")
    with pytest.raises(InputError, match="uint8"):
        write_png(tmp_path / "f.png", np.zeros((2, 2), np.float32))
    with pytest.raises(InputError, match="2-D"):
        write_tiff(tmp_path / "f.tif", np.zeros((2, 2, 2)))
    with pytest.raises(SatchainIOError, match="does not exist"):
        write_npy(tmp_path / "nodir" / "a.npy", np.zeros(2))
    with pytest.raises(InputError, match="multiples of 16"):
        write_tiff(tmp_path / "g.tif", np.zeros((4, 4)), tile=(10, 10))
    assert not (tmp_path / "f.png").exists() and not (tmp_path / "g.tif").exists()
