"""The README's mesh picture: the tanglecube ray-traced by `implgen render`, beside the wireframe of its mesh
from `implgen mesh` (matplotlib), seen from the same side.

    .venv/bin/python bench/mesh_picture.py [-o docs/gallery/mesh.png]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "examples/mesh/tanglecube.yaml"
SCENE = """image: {width: 480, height: 480, spp: 4, max_depth: 3}
camera: {position: [7.0, 5.0, 7.0], look_at: [0, 0, 0], up: [0, 1, 0], fov: 36}
background: [1, 1, 1]
lights:
  - {position: [8, 10, 6], color: [1, 1, 1], intensity: 1.0}
materials:
  body: {color: [0.85, 0.45, 0.3], ambient: 0.15, diffuse: 0.7, specular: 0.4, shininess: 40}
objects:
  - {shape: SPEC, material: body}
"""


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("-o", "--output", default=str(ROOT / "docs/gallery/mesh.png"))
    ap.add_argument("--cells", type=int, default=20)
    args = ap.parse_args()
    implgen = str(Path(sys.executable).parent / "implgen")
    with tempfile.TemporaryDirectory() as tmp:
        scene, png, stl = Path(tmp) / "s.yaml", Path(tmp) / "r.png", Path(tmp) / "m.ply"
        scene.write_text(SCENE.replace("SPEC", str(SPEC)))
        subprocess.run([implgen, "render", str(scene), "-o", str(png)], check=True)
        subprocess.run([implgen, "mesh", str(SPEC), "--cells", str(args.cells), "-o", str(stl)], check=True)
        picture = plt.imread(png)
        mesh = trimesh.load(stl, force="mesh")
    fig = plt.figure(figsize=(9.6, 4.8), dpi=100)
    ax = fig.add_subplot(1, 2, 1)
    ax.imshow(picture)
    ax.set_axis_off()
    ax.set_title("implgen render", fontsize=10)
    ax3 = fig.add_subplot(1, 2, 2, projection="3d")
    v = np.asarray(mesh.vertices)[:, [0, 2, 1]]  # the scene's y is up; matplotlib's z is
    ax3.add_collection3d(Line3DCollection(v[np.asarray(mesh.edges_unique)], colors="0.2", linewidths=0.35))
    ax3.set_xlim(-2.6, 2.6), ax3.set_ylim(-2.6, 2.6), ax3.set_zlim(-2.6, 2.6)
    ax3.set_box_aspect((1, 1, 1))
    ax3.view_init(elev=30, azim=45)
    ax3.set_axis_off()
    ax3.set_title(
        f"implgen mesh --cells {args.cells}: {len(mesh.faces)} triangles, Euler {mesh.euler_number}", fontsize=10
    )
    fig.tight_layout()
    fig.savefig(args.output)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
