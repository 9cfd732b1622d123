"""A page's scene libraries: each built (or found in the build cache) once per set of shapes on the parse pool,
then reused by every page showing those shapes (each render maps the scene's leaves onto it on its own thread);
a build that lasts more than a moment is told to the page as it goes."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable

from implgen.scene.build import BuildResult, build_scene, runtime_ready
from implgen.scene.model import Scene
from implgen.view.work import Work

BUILD_QUIET, BUILD_POLL = 0.2, 0.4  # seconds: a build says nothing before the first, then repeats its progress


class Builds:
    def __init__(self, work: Work, send: Callable[[dict], Awaitable[None]]):
        self.work = work
        self.send = send
        self._told = False  # the page was told a build is going on

    async def library(self, sc: Scene) -> BuildResult:
        """The scene's library, from the pools' shared ones or built now."""
        specs = sc.specs()
        built = self.work.library(specs)
        if built is None:
            telling = asyncio.get_running_loop().create_task(self._tell())
            try:
                built = await self.work.call(self.work.parse, build_scene, sc)
            finally:
                telling.cancel()
                if self._told:
                    self._told = False
                    await self.send({"type": "status", "text": ""})
            self.work.keep_library(specs, built)
        return built

    async def _tell(self) -> None:
        """While a build lasts more than a moment: what it does, for the page's status ("compiling the runtime
        (first run only): 3 of N files", once per build cache; then the shape)."""
        await asyncio.sleep(BUILD_QUIET)
        while True:
            done, total = await asyncio.to_thread(runtime_ready)
            if done < total:
                text = f"compiling the runtime (first run only): {done} of {total} files"
            else:
                text = "compiling the shape"
            self._told = True
            await self.send({"type": "status", "text": text})
            await asyncio.sleep(BUILD_POLL)
