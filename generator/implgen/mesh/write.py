"""A mesh to a file, written by trimesh (binary STL, OBJ, binary PLY with doubles, glTF binary), atomically; the
per-vertex normals the formats that hold them get: the gradient of the piece that bounds the solid there
(f, or a clip), normalised; the faces' average where that gradient vanishes (a node)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from implgen.mesh.crossings import boundary_value_gradient, unit
from implgen.mesh.region import Clip
from implgen.mesh.shapelib import ShapeLib
from implgen.outputs import atomic_write

FORMATS = {".stl": "stl", ".obj": "obj", ".ply": "ply", ".glb": "glb"}


def vertex_normals(lib: ShapeLib, clips: list[Clip], verts: np.ndarray) -> np.ndarray:
    """Unit normals toward f > 0 (zero where the bounding piece's gradient vanishes)."""
    _, g = boundary_value_gradient(lib, clips, verts)
    return unit(g)


def to_trimesh(verts: np.ndarray, faces: np.ndarray, normals: np.ndarray | None = None):
    import trimesh

    mesh = trimesh.Trimesh(vertices=verts, faces=faces, process=False, validate=False)
    if normals is not None:
        bad = np.linalg.norm(normals, axis=1) == 0
        if bad.any():  # the faces' area-weighted normals there (trimesh computes them for the whole mesh)
            normals = np.where(bad[:, None], np.asarray(mesh.vertex_normals), normals)
        mesh.vertex_normals = normals
    return mesh


def place(matrix: np.ndarray, verts: np.ndarray, faces: np.ndarray, normals: np.ndarray):
    """(verts, faces, normals) moved object -> world by a 3x4 matrix: normals by the inverse transpose, the faces
    turned by a mirror so they still face f > 0."""
    lin = matrix[:, :3]
    verts = verts @ lin.T + matrix[:, 3]
    normals = normals @ np.linalg.inv(lin)
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    if np.linalg.det(lin) < 0:
        faces = faces[:, ::-1]
    return verts, faces, normals


def write_mesh(path: Path, verts: np.ndarray, faces: np.ndarray, normals: np.ndarray | None) -> None:
    """Write in the format the suffix names (FORMATS); STL is binary."""
    blob = mesh_bytes(FORMATS[path.suffix.lower()], verts, faces, normals)
    atomic_write(path, lambda fh: fh.write(blob))  # type: ignore[attr-defined]


def mesh_bytes(kind: str, verts: np.ndarray, faces: np.ndarray, normals: np.ndarray | None) -> bytes:
    """The file's bytes, `kind` one of FORMATS' values."""
    mesh = to_trimesh(verts, faces, normals)
    if kind == "obj":  # 17 significant digits: the doubles exactly (trimesh's default keeps 8 decimals)
        data = mesh.export(file_type=kind, include_normals=True, digits=17)
    elif kind == "ply":
        data = mesh.export(file_type=kind, vertex_normal=True)
    else:  # binary STL (float32, as the format holds), glTF binary (float32)
        data = mesh.export(file_type=kind)
    return data.encode("utf-8") if isinstance(data, str) else bytes(data)
