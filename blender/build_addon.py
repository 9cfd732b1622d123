"""Zip the Blender add-on: `python blender/build_addon.py out/implgen_blender.zip` (what `make blender-addon`
runs). One folder, implgen_blender/, holding the add-on's files and implgen's LICENSE; the same bytes every time
(fixed dates and modes), and nothing else from the folder (no __pycache__)."""

from __future__ import annotations

import sys
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
FILES = {name: HERE / "implgen_blender" / name for name in ("__init__.py", "surface.py", "blender_manifest.toml")}
FILES["LICENSE"] = HERE.parent / "LICENSE"


def build(target: Path) -> Path:
    target.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(target, "w") as zf:
        for name, source in FILES.items():
            info = zipfile.ZipInfo(f"implgen_blender/{name}", date_time=(1980, 1, 1, 0, 0, 0))
            info.external_attr = 0o644 << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            zf.writestr(info, source.read_bytes())
    return target


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python blender/build_addon.py OUT.zip")
    print(build(Path(sys.argv[1])))
