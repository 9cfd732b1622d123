"""A mesh to a file, atomically: binary STL and glTF binary (float32, as those formats hold) written by trimesh;
OBJ (every double in its shortest exact decimal form) and binary PLY (doubles) written here, both plain formats
that trimesh's own writers would round (PLY to float32, OBJ to a fixed count of decimals). The per-vertex
normals the formats that hold them get: the gradient of the piece that bounds the solid there (f, or a clip),
normalised; the faces' average where that gradient vanishes (a node)."""

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
    if kind == "obj":
        return obj_bytes(np.asarray(mesh.vertices), faces, np.asarray(mesh.vertex_normals))
    if kind == "ply":
        return ply_bytes(np.asarray(mesh.vertices), faces, np.asarray(mesh.vertex_normals))
    data = mesh.export(file_type=kind)  # binary STL (float32, as the format holds), glTF binary (float32)
    return data.encode("utf-8") if isinstance(data, str) else bytes(data)


def obj_bytes(verts: np.ndarray, faces: np.ndarray, normals: np.ndarray) -> bytes:
    """Wavefront OBJ: `v` and `vn` lines, each double as Python's repr writes it (the shortest decimal that reads
    back as the same double), and `f a//a b//b c//c` lines (1-based, the vertex's own normal)."""
    lines = ["# implgen mesh"]
    lines += map("v {!r} {!r} {!r}".format, *np.asarray(verts, dtype=np.float64).T.tolist())
    lines += map("vn {!r} {!r} {!r}".format, *np.asarray(normals, dtype=np.float64).T.tolist())
    lines += map("f {0}//{0} {1}//{1} {2}//{2}".format, *(np.asarray(faces, dtype=np.int64) + 1).T.tolist())
    return ("\n".join(lines) + "\n").encode("ascii")


PLY_VERTEX = np.dtype([(k, "<f8") for k in ("x", "y", "z", "nx", "ny", "nz")])
PLY_FACE = np.dtype([("count", "u1"), ("index", "<i4", (3,))])


def ply_bytes(verts: np.ndarray, faces: np.ndarray, normals: np.ndarray) -> bytes:
    """Binary little-endian PLY: per vertex x, y, z and nx, ny, nz as doubles; per face a list of three ints."""
    vert = np.empty(len(verts), dtype=PLY_VERTEX)
    for k, name in enumerate(("x", "y", "z")):
        vert[name], vert["n" + name] = verts[:, k], normals[:, k]
    face = np.empty(len(faces), dtype=PLY_FACE)
    face["count"], face["index"] = 3, faces
    head = ["ply", "format binary_little_endian 1.0", "comment implgen mesh", f"element vertex {len(verts)}"]
    head += [f"property double {name}" for name in PLY_VERTEX.names]
    head += [f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header"]
    return ("\n".join(head) + "\n").encode("ascii") + vert.tobytes() + face.tobytes()
