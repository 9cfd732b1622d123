"""The refinement ladder: how a resting view is refined, pass by pass, in one C render context.

When the view rests, the page first gets a picture it can show at once, then better ones, and last the picture
`implgen render` makes of the view at its samples a pixel (the viewer's 4), bit for bit:

    quarter  sample 0 of the pixels whose x and y are even: a half-size picture (a quarter of the pixels), sent
             when the page shows something smaller (the drag's last coarse frame)
    one      sample 0 of the other pixels: the whole picture at 1 sample (sample 0 of the stratified pattern)
    more     samples added to the sums, a pass at a time, each pass about PASS_TARGET seconds: the mean so far
    full     the last pass: every sample, the whole render's image

No sample is rendered twice: the passes add the whole render's own samples, in its order, to running sums in
double (RenderJob.run_pass, rt_render_set_pass), so the ladder costs what the whole render costs plus an
encoding a step. A view whose whole picture is expected within REFINE_TARGET gets it in one pass.
`refine` runs the steps on the render pool under one Ticket (each pass has the render budget) and sends each
picture from the event loop as its pass ends.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

import numpy as np

from implgen.imagefile import to_uint8
from implgen.scene.build import BuildResult
from implgen.scene.model import Scene
from implgen.scene.renderjob import PIXELS_ALL, PIXELS_EVEN, PIXELS_ODD, RenderJob
from implgen.scene.tracer import CScene
from implgen.view import frames
from implgen.view.work import Ticket, Work

REFINE_TARGET = 0.4  # seconds: a whole picture expected within this is rendered in one pass
PASS_TARGET = 1.0  # seconds: samples are added in passes expected to take about this long (one sample at least)
SHARE = {PIXELS_ALL: 1.0, PIXELS_EVEN: 0.25, PIXELS_ODD: 0.75}  # the share of the pixels a pass renders


@dataclass(frozen=True)
class Step:
    """One pass: samples [k0, k1) of `pixels`; `role` says what its picture is (quarter, one, more, full)."""

    role: str
    k0: int
    k1: int
    pixels: int = PIXELS_ALL


def plan(width: int, height: int, spp: int, per_pixel: float | None, small: bool) -> list[Step]:
    """The steps refining a width x height view to spp samples. `per_pixel`: the wall time of a pixel at one
    sample the live frames measured (None: not known); `small`: the page shows a picture smaller than a quarter
    of this one, so a half-size picture comes first."""
    frame = None if per_pixel is None else per_pixel * width * height  # the whole picture at one sample
    if frame is not None and frame * spp <= REFINE_TARGET:
        return [Step("full", 0, spp)]
    steps = [Step("quarter", 0, 1, PIXELS_EVEN), Step("one", 0, 1, PIXELS_ODD)] if small else [Step("one", 0, 1)]
    per_pass = spp if frame is None else max(1, int(PASS_TARGET / frame))
    k = 1
    while k < spp:
        k1 = min(spp, k + per_pass)
        steps.append(Step("full" if k1 == spp else "more", k, k1))
        k = k1
    if spp == 1:
        steps[-1] = Step("full", 0, 1, steps[-1].pixels)
    return steps


@dataclass(frozen=True)
class Picture:
    """A step's picture, encoded: what the page is sent."""

    step: Step
    width: int
    height: int
    data: bytes
    empty: bool  # nothing but the background


def _picture(step: Step, img: np.ndarray, background: np.ndarray) -> Picture:
    """A pass's picture as PNG: the even pixels alone (half size) after their pass, else the whole image."""
    rgb8 = frames.eight_bits(img[::2, ::2] if step.pixels == PIXELS_EVEN else img)
    return Picture(step, rgb8.shape[1], rgb8.shape[0], frames.live_png(rgb8), bool((rgb8 == background).all()))


def run(
    ticket: Ticket,
    loop,
    sc: Scene,
    lib: BuildResult,
    steps: list[Step],
    threads: int,
    deliver: Callable[[Picture], None],
) -> bool:
    """On a pool thread: the steps' passes in one C render context of `sc` (at its spp), each picture encoded and
    handed to `deliver` (on this thread: it must only schedule the sending); True when every pass ran, False
    when one was cancelled (by the page, or by the budget: ticket.expired says which)."""
    if ticket.cancelled:
        return False
    background = to_uint8(np.asarray(sc.background, np.float32).reshape(1, 1, 3))
    cs = CScene(sc, lib.for_scene(sc, fold=False))
    try:
        with RenderJob(cs, sc.width, sc.height, sc.spp, sc.max_depth, threads) as job:
            for step in steps:
                ticket.begin_pass(step.k1 - step.k0, SHARE[step.pixels])
                ticket.attach(job, loop)
                try:
                    img = job.run_pass(step.k0, step.k1, step.pixels)
                finally:
                    ticket.detach()
                if img is None:
                    return False
                deliver(_picture(step, img, background))
                ticket.shown = step.k1 if step.pixels != PIXELS_EVEN else 0
    finally:
        cs.close()
    return True


async def refine(
    work: Work,
    ticket: Ticket,
    sc: Scene,
    lib: BuildResult,
    steps: list[Step],
    threads: int,
    send: Callable[[Picture], Awaitable[None]],
) -> bool:
    """The steps (`run`) on the render pool under `ticket`, each picture sent as it comes, in order, while the next
    pass renders: whether every pass ran. A cancelled caller cancels the run and waits for it to stop."""
    loop = asyncio.get_running_loop()
    pictures: asyncio.Queue = asyncio.Queue()

    def deliver(picture: Picture) -> None:  # on the pool's thread
        loop.call_soon_threadsafe(pictures.put_nowait, picture)

    task = loop.create_task(work.trace(work.render, ticket, run, sc, lib, steps, threads, deliver))
    try:
        while not task.done():
            got = asyncio.ensure_future(pictures.get())
            try:
                await asyncio.wait({got, task}, return_when=asyncio.FIRST_COMPLETED)
            finally:
                waiting = not got.done()
                if waiting:  # the run has ended (or the caller was cancelled): nothing more to wait for
                    got.cancel()
            if waiting:
                break
            await send(got.result())
        while not pictures.empty():  # the run's last pictures were queued before it ended
            await send(pictures.get_nowait())
        return task.result()
    finally:
        if not task.done():
            task.cancel()
            await asyncio.gather(task, return_exceptions=True)
