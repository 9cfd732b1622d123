"""Frames to their files, in order, without holding up the render.

Every frame file is complete before it has its name, even after a power loss: written to a temporary name,
flushed to the disk (fsync), then renamed (frameout.FrameOutput.stage, commit). A flush waits for the disk,
several ms a frame on the machines measured, longer than a small frame's render. So `OrderedWriter` stages
frames on a few threads at once (encoding those that come as pixels) while the render goes on, and renames
each into place in frame order once it and every frame before it are staged: a rerun after a crash finds a
prefix of complete frames plus what the next ones completed, never a partial one. It holds at most `depth`
frames or `max_bytes` of pixels and PNGs not yet in place; beyond that `put` waits.
"""

from __future__ import annotations

import threading
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

from implgen.animation.frameout import FrameOutput
from implgen.errors import UserError

THREADS = 4  # flushes in flight: the disk takes them together
DEPTH = 64  # frames staged or staging, not yet in place
MAX_BYTES = 256 << 20  # their pixels and PNG bytes


class OrderedWriter:
    """Frames to `out`: `put(frame, image)` in frame order; each call returns the frames now in place."""

    def __init__(self, out: FrameOutput, threads: int = THREADS, depth: int = DEPTH, max_bytes: int = MAX_BYTES):
        self.out = out
        self.depth, self.max_bytes = depth, max_bytes
        self.pool = ThreadPoolExecutor(threads, thread_name_prefix="implgen-write")
        self.pending: deque[tuple[int, Future, int]] = deque()
        self.held = 0  # bytes of the pending frames
        self.staged: set[Path] = set()  # temporary files made and not renamed yet, whatever `pending` says
        self._lock = threading.Lock()

    def put(self, frame: int, image) -> list[int]:
        size = len(image) if isinstance(image, bytes) else image.nbytes
        self.pending.append((frame, self.pool.submit(self._stage, image), size))
        self.held += size
        return self._commit(final=False)

    def _stage(self, image) -> Path:
        tmp = self.out.stage(image)
        with self._lock:
            self.staged.add(tmp)
        return tmp

    def close(self) -> list[int]:
        """Every frame put, in place; then the threads end."""
        done = self._commit(final=True)
        self.pool.shutdown(wait=True)
        return done

    def abandon(self) -> None:
        """After an error or an interrupt (which may have come at any point of `put`): the staging in progress
        waited for, and every staged frame not in place removed (a crash would have left them as temporary
        files, never taken for frames)."""
        for _, fut, _ in self.pending:
            fut.cancel()
        self.pool.shutdown(wait=True)
        self.pending.clear()
        with self._lock:
            left, self.staged = self.staged, set()
        for tmp in left:
            tmp.unlink(missing_ok=True)  # missing: renamed into place just before the interrupt

    def _commit(self, final: bool) -> list[int]:
        """Rename the staged frames at the head into place: all of them when `final`, else those ready and as
        many more as bring the pending frames within the bounds."""
        done = []
        while self.pending:
            frame, fut, size = self.pending[0]
            over = len(self.pending) > self.depth or self.held > self.max_bytes
            if not (final or over or fut.done()):
                break
            try:
                tmp = fut.result()
                self.out.commit(frame, tmp)
                with self._lock:
                    self.staged.discard(tmp)
            except OSError as err:  # a full disk, a folder removed meanwhile: one line, the frames so far kept
                raise UserError(f"-o {self.out.target}", f"cannot write frame {frame}: {err.strerror or err}") from None
            self.pending.popleft()
            self.held -= size
            done.append(frame)
        return done
