"""The size of the live (coarse) frames while the user drags: chosen so that a frame takes about TARGET seconds,
whatever the degree, the scene or the zoom, from what the last frames of this page took.

A coarse frame in flight is never thrown away by the next move (session.py): it is finished and sent, and the
newest request is drawn next. So the frame rate is 1 / (time of a frame), and the frame's size is what keeps it
near 30 frames a second. The measure is the wall time of a whole frame (scene, C render, encoding) over its
pixels; the next size is the one that measure says takes TARGET, never more than GROW times the pixels of the
last one (a measure from a tiny frame is mostly fixed costs), between MIN_WIDTH pixels a row and the full frame.

A frame that runs past CUT seconds is cut (cancelled in C) unless it is already the smallest: its rows done say
what a pixel costs, so the next one is small enough. The first frame of a new shape starts from the last size
scaled down by FIRST_SHRINK in pixels: a new shape may cost a hundred times the last one.
"""

from __future__ import annotations

import math

TARGET = 0.030  # seconds a live frame should take while dragging
CUT = 0.25  # seconds after which a live frame larger than the smallest is cut
MIN_WIDTH = 48  # pixels a row of the smallest live frame
MAX_DIVISOR = 2  # a live frame is at most half the full frame's width and height
GROW = 2.0  # at most this many times the pixels of the last frame
FIRST_SHRINK = 4.0  # a new shape's first frame: the last size's pixels divided by this
START_PIXELS = 160 * 120  # the first frame of a page


class Pace:
    """One page's live-frame size, learned from the frames it has drawn."""

    def __init__(self) -> None:
        self.pixels = float(START_PIXELS)  # the next frame's pixel count (before the frame's limits)
        self.seconds_per_pixel: float | None = None  # the last measure

    def size(self, width: int, height: int) -> tuple[int, int]:
        """The next live frame for a full frame of width x height: the same aspect, its pixels as learned."""
        most = max(1, width // MAX_DIVISOR) * max(1, height // MAX_DIVISOR)
        least_w = min(MIN_WIDTH, width)
        least = least_w * max(1, round(least_w * height / width))
        pixels = min(max(self.pixels, least), most)
        scale = math.sqrt(pixels / (width * height))
        return max(1, min(width, round(width * scale))), max(1, min(height, round(height * scale)))

    def smallest(self, width: int, height: int, w: int) -> bool:
        """Whether a live frame w pixels wide is the smallest this page draws (it is never cut)."""
        return w <= min(MIN_WIDTH, width)

    def measured(self, pixels: int, seconds: float) -> None:
        """A live frame of `pixels` took `seconds` (whole: scene, render, encoding); or, for a cut frame, the
        part of it that was done (its rows' pixels) took `seconds`."""
        if pixels <= 0 or seconds <= 0:
            return
        self.seconds_per_pixel = seconds / pixels
        self.pixels = min(TARGET / self.seconds_per_pixel, GROW * pixels)

    def cut(self, pixels: int) -> None:
        """A frame of `pixels` was cut with no row done: a pixel costs more than CUT / pixels a row."""
        self.pixels = pixels / (FIRST_SHRINK * FIRST_SHRINK)

    def new_shape(self) -> None:
        self.pixels = self.pixels / FIRST_SHRINK
