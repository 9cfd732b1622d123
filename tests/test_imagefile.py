"""implgen.imagefile: the one 8-bit conversion, PNG/JPEG encoder, decoder and PNG file writer."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image

from implgen.imagefile import decode_png, encode_jpeg, encode_png, to_uint8, write_png


def _image() -> np.ndarray:
    y, x = np.mgrid[0:23, 0:37]
    img = np.stack([x / 36.0, y / 22.0, (x * y) % 7 / 6.0], axis=-1).astype(np.float32)
    img[0, 0] = (np.nan, -0.5, 1.5)  # NaN as 0, clamped below and above
    img[0, 1] = (0.5 / 255.0, 1.49 / 255.0, 254.5 / 255.0)  # rounding to the nearest level
    return img


def test_to_uint8_clamps_and_rounds() -> None:
    rgb8 = to_uint8(_image())
    assert rgb8.dtype == np.uint8 and rgb8.shape == (23, 37, 3)
    assert rgb8[0, 0].tolist() == [0, 0, 255]
    assert rgb8[0, 1].tolist() == [1, 1, 255]
    assert rgb8[22, 36, :2].tolist() == [255, 255]


def test_png_round_trips_at_every_level() -> None:
    rgb8 = to_uint8(_image())
    default = encode_png(rgb8)
    assert np.array_equal(decode_png(default), rgb8)
    fast = encode_png(rgb8, compress_level=1)
    assert np.array_equal(decode_png(fast), rgb8) and fast != default  # other bytes, same pixels


def test_the_default_png_is_pillows_plain_save(tmp_path) -> None:
    """write_png's file, the bytes encode_png gives, and Pillow's save with no options are the same bytes
    (what `implgen render` always wrote; the viewer's saved picture is the same encoder in memory)."""
    img = _image()
    write_png(img, tmp_path / "a.png")
    buf = io.BytesIO()
    Image.fromarray(to_uint8(img), mode="RGB").save(buf, format="PNG")
    assert (tmp_path / "a.png").read_bytes() == encode_png(to_uint8(img)) == buf.getvalue()
    assert [p.name for p in tmp_path.iterdir()] == ["a.png"]  # no temporary file left beside it


def test_jpeg_is_a_close_preview() -> None:
    y, x = np.mgrid[0:48, 0:64]
    rgb8 = to_uint8(np.stack([x / 63.0, y / 47.0, 0.5 + 0 * x], axis=-1))  # smooth: what JPEG keeps
    data = encode_jpeg(rgb8, quality=88)
    assert data[:2] == b"\xff\xd8"
    with Image.open(io.BytesIO(data)) as im:
        back = np.asarray(im.convert("RGB")).astype(int)
    assert back.shape == rgb8.shape and np.abs(back - rgb8).max() <= 4
