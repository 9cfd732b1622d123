"""A page's frames: one C render of a scene under its ticket (on a pool thread), and the bytes it is sent as
(the coarse frame as JPEG, the full frame as fast PNG, a saved picture as the PNG `implgen render` writes)."""

from __future__ import annotations

import numpy as np

from implgen.imagefile import encode_jpeg, encode_png, to_uint8
from implgen.scene.build import BuildResult
from implgen.scene.model import Scene
from implgen.scene.renderjob import RenderJob
from implgen.scene.tracer import CScene
from implgen.view.work import Ticket

LIVE_JPEG_QUALITY = 88  # the coarse frame: small and soon replaced
LIVE_PNG_LEVEL = 1  # the full frame: speed over size (zlib level 1)
BAND = 256  # rows converted to 8 bits at a time: no float temporaries the size of a whole saved picture


def live_jpeg(rgb8: np.ndarray) -> bytes:
    return encode_jpeg(rgb8, LIVE_JPEG_QUALITY)


def live_png(rgb8: np.ndarray) -> bytes:
    return encode_png(rgb8, LIVE_PNG_LEVEL)


def file_png(rgb8: np.ndarray) -> bytes:
    return encode_png(rgb8)  # the encoder and level write_png uses: the bytes `implgen render` writes


def eight_bits(img: np.ndarray) -> np.ndarray:
    """to_uint8 band by band (the same values as on the whole picture, a fraction of its temporaries)."""
    out = np.empty(img.shape, np.uint8)
    for y in range(0, img.shape[0], BAND):
        out[y : y + BAND] = to_uint8(img[y : y + BAND])
    return out


def trace(ticket: Ticket, loop, sc: Scene, lib: BuildResult, spp: int, threads: int, encode):
    """On a pool thread: one C render of `sc` under its ticket, encoded, and whether it shows nothing but the
    background; None when cancelled (by the page, or by the budget: ticket.expired says which). The same
    context and samples as render() (renderjob.py)."""
    if ticket.cancelled:
        return None
    cs = CScene(sc, lib.for_scene(sc, fold=False))
    try:
        with RenderJob(cs, sc.width, sc.height, spp, sc.max_depth, threads) as job:
            ticket.attach(job, loop)
            try:
                img = job.run()
            finally:
                ticket.detach()
            rgb8 = None if img is None else eight_bits(img)
            job.image = img = None  # the float picture is not kept while the bytes are encoded
    finally:
        cs.close()
    if rgb8 is None:
        return None
    background = to_uint8(np.asarray(sc.background, np.float32).reshape(1, 1, 3))
    return encode(rgb8), bool((rgb8 == background).all())
