"""Pictures as bytes and files: the one place an image is turned into 8 bits, encoded, decoded or written.

A rendered image is float32 (height, width, 3), linear and not clamped (scene/render.py). `to_uint8` makes
it 8-bit RGB (NaN as 0, clamped to [0, 1], rounded); the encoders take that. PNG is Pillow's with its default
options unless a compression level is asked for (the live view asks for 1: speed over size), so every
PNG the tools write for one image is the same bytes. JPEG is for the live view's coarse frames only.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from implgen.outputs import atomic_write


def to_uint8(img: np.ndarray) -> np.ndarray:
    """A float image -> 8-bit RGB: NaN as 0, clamped to [0, 1], rounded to the nearest level."""
    return (np.clip(np.nan_to_num(img, nan=0.0), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def _picture(rgb8: np.ndarray):
    from PIL import Image  # not at import: `import implgen` and the commands that write no picture stay light

    return Image.fromarray(rgb8, mode="RGB")


def encode_png(rgb8: np.ndarray, compress_level: int | None = None) -> bytes:
    """8-bit RGB -> PNG bytes; `compress_level` 0-9, None for Pillow's default (what files are written with)."""
    buf = io.BytesIO()
    if compress_level is None:
        _picture(rgb8).save(buf, format="PNG")
    else:
        _picture(rgb8).save(buf, format="PNG", compress_level=compress_level)
    return buf.getvalue()


def encode_jpeg(rgb8: np.ndarray, quality: int) -> bytes:
    """8-bit RGB -> JPEG bytes (lossy: only for previews that a lossless frame replaces)."""
    buf = io.BytesIO()
    _picture(rgb8).save(buf, format="JPEG", quality=quality)
    return buf.getvalue()


def decode_png(data: bytes) -> np.ndarray:
    """PNG bytes -> 8-bit RGB (height, width, 3)."""
    from PIL import Image

    with Image.open(io.BytesIO(data)) as im:
        return np.asarray(im.convert("RGB"))


def write_png(img: np.ndarray, path: str | Path) -> None:
    """A float image to a PNG file, written atomically (outputs.atomic_write): a failure leaves nothing
    half-written."""
    data = encode_png(to_uint8(img))
    atomic_write(Path(path), lambda fh: fh.write(data))


def write_grey_png(values: np.ndarray, path: str | Path) -> None:
    """An 8-bit grey image (height, width) of uint8 values to a PNG file as they are (the certify map: codes,
    not brightness), written atomically."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(values, dtype=np.uint8), mode="L").save(buf, format="PNG")
    data = buf.getvalue()
    atomic_write(Path(path), lambda fh: fh.write(data))
