"""The PNG writer and reader: round trips, and Pillow (where installed) as an independent reader."""

from __future__ import annotations

import io
import zlib

import numpy as np
import pytest

from p3d_cli.render.png import decode_png, encode_png


@pytest.mark.parametrize("channels", [3, 4])
def test_round_trip_is_exact(channels):
    rng = np.random.default_rng(1)
    pixels = rng.integers(0, 256, size=(37, 53, channels), dtype=np.uint8)
    assert np.array_equal(decode_png(encode_png(pixels)), pixels)


def test_pillow_reads_what_we_write():
    image_module = pytest.importorskip("PIL.Image")
    rng = np.random.default_rng(2)
    pixels = rng.integers(0, 256, size=(20, 31, 3), dtype=np.uint8)
    with image_module.open(io.BytesIO(encode_png(pixels, text={"Title": "x"}))) as image:
        assert image.size == (31, 20) and image.mode == "RGB"
        assert np.array_equal(np.asarray(image), pixels)


def test_we_read_every_filter_pillow_writes():
    image_module = pytest.importorskip("PIL.Image")
    # A gradient with noise makes Pillow's encoder choose among the filters row by row.
    y, x = np.mgrid[0:24, 0:40]
    rng = np.random.default_rng(3)
    pixels = np.stack([x * 6, y * 10, (x * y) % 256], axis=-1).astype(np.uint8)
    pixels[::5] = rng.integers(0, 256, size=pixels[::5].shape, dtype=np.uint8)
    out = io.BytesIO()
    image_module.fromarray(pixels).save(out, format="PNG", optimize=True)
    assert np.array_equal(decode_png(out.getvalue()), pixels)


def test_refuses_what_is_not_an_rgb_array():
    with pytest.raises(ValueError):
        encode_png(np.zeros((4, 4), dtype=np.uint8))
    with pytest.raises(ValueError):
        encode_png(np.zeros((4, 4, 3), dtype=np.float64))
    with pytest.raises(ValueError, match="signature"):
        decode_png(b"GIF89a")


def test_a_corrupt_image_is_refused():
    data = bytearray(encode_png(np.zeros((8, 8, 3), dtype=np.uint8)))
    start = data.index(b"IDAT") + 4
    data[start:start + 4] = b"\0\0\0\0"
    with pytest.raises((ValueError, zlib.error)):
        decode_png(bytes(data))
