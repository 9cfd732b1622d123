"""A triangle mesh's own checks: every edge in exactly two triangles, once each way (closed and oriented), the
Euler characteristic, and every vertex's triangles one fan (a 2-manifold at the vertex, not two cones touching)."""

from __future__ import annotations

import numpy as np


def closed_and_euler(faces: np.ndarray, nverts: int) -> tuple[bool, int]:
    """(every edge in exactly two faces, each way once; V - E + F over the vertices faces use). Edges are keyed
    as one integer each (u n + v), so a sort of integers finds them: millions of faces in a second."""
    if not len(faces):
        return False, 0
    n = max(int(nverts), int(faces.max()) + 1)
    a, b = faces.reshape(-1).astype(np.int64), faces[:, [1, 2, 0]].reshape(-1).astype(np.int64)
    directed = np.sort(a * n + b)
    und = np.sort(np.minimum(a, b) * n + np.maximum(a, b))
    first = np.flatnonzero(np.concatenate([[True], und[1:] != und[:-1]]))
    counts = np.diff(np.append(first, und.size))
    closed = bool((counts == 2).all()) and bool((directed[1:] != directed[:-1]).all())
    used = int(np.count_nonzero(np.bincount(faces.reshape(-1), minlength=n)))
    return closed, used - int(first.size) + len(faces)


def one_fan_each(faces: np.ndarray, only: np.ndarray | None = None) -> bool:
    """Whether the triangles around every vertex (of `only`, when given) form one cycle. Of a closed, oriented
    mesh: triangle (a, b, c) gives a the link edge b -> c, b the edge c -> a, c the edge a -> b; around a vertex
    these form cycles, one per fan. Each link node (vertex, neighbour) takes the least label along its cycle;
    one label per vertex."""
    if only is not None:
        faces = faces[np.isin(faces, only).any(axis=1)]  # every triangle around those vertices
    if not len(faces):
        return True
    f = faces.astype(np.int64)
    n = int(f.max()) + 1
    centre = f.reshape(-1)
    src = f[:, [1, 2, 0]].reshape(-1)
    dst = f[:, [2, 0, 1]].reshape(-1)
    keys, inv = np.unique(np.concatenate([centre * n + src, centre * n + dst]), return_inverse=True)
    a, b = inv[: centre.size], inv[centre.size :]
    label = np.arange(keys.size)
    while True:
        low = np.minimum(label[a], label[b])
        new = label.copy()
        np.minimum.at(new, a, low)
        np.minimum.at(new, b, low)
        new = new[new]  # pointer jumping: cycles of any length in few rounds
        if np.array_equal(new, label):
            break
        label = new
    fans = np.unique((keys // n) * keys.size + label) // keys.size  # a vertex once per fan
    if only is not None:
        fans = fans[np.isin(fans, only)]
    return bool((np.bincount(fans) <= 1).all())
