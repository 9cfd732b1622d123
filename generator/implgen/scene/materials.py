"""Materials in a scene file: the `materials` block (name -> material) and a material given by name or written
in place on an object."""

from __future__ import annotations

from typing import Any

from implgen import validate
from implgen.scene.model import Material
from implgen.scene.reader import Reader

MATERIAL_KEYS = (
    "color",
    "checker",
    "ambient",
    "diffuse",
    "specular",
    "shininess",
    "reflectivity",
    "transparency",
    "ior",
    "absorption",
    "inside",
)
# Documented ranges of the material terms ([lo, hi])
MATERIAL_RANGES = {
    "ambient": (0.0, 100.0),
    "diffuse": (0.0, 100.0),
    "specular": (0.0, 100.0),
    "shininess": (0.0, 1e4),
    "reflectivity": (0.0, 1.0),
    "transparency": (0.0, 1.0),
}
IOR_MAX = 10.0
ABSORPTION_MAX = 1e6


def parse_material(ctx: Reader, key: str, raw: Any) -> Material:
    raw = ctx.mapping(key, raw, MATERIAL_KEYS)
    m = Material()
    if "color" in raw:
        m.color = ctx.color(f"{key}.color", raw["color"])
    if "checker" in raw:
        ch = ctx.mapping(f"{key}.checker", raw["checker"], ("colors", "scale"))
        cols = ch.get("colors")
        if not isinstance(cols, list) or len(cols) != 2:
            raise ctx.fail(f"{key}.checker.colors", "expected two colours")
        m.color = ctx.color(f"{key}.checker.colors[0]", cols[0])
        m.color2 = ctx.color(f"{key}.checker.colors[1]", cols[1])
        m.checker_scale = ctx.num(f"{key}.checker.scale", ch.get("scale", 1.0), 0.0, lo_open=True)
    for k, (lo, hi) in MATERIAL_RANGES.items():
        if k in raw:
            setattr(m, k, ctx.num(f"{key}.{k}", raw[k], lo, hi))
    if "ior" in raw:
        m.ior = ctx.num(f"{key}.ior", raw["ior"], 0.0, IOR_MAX, lo_open=True)
    if "absorption" in raw:
        m.absorption = ctx.vec(f"{key}.absorption", raw["absorption"], 0.0, ABSORPTION_MAX)
    if "inside" in raw:  # two-sided: the colour of the back (f < 0) side of a surface
        m.inside = ctx.color(f"{key}.inside", raw["inside"])
    return m


def material_ref(ctx: Reader, key: str, raw: Any, named: dict[str, Material]) -> Material:
    if isinstance(raw, str):
        if raw not in named:
            known = ", ".join(sorted(named)) or "none defined"
            raise ctx.fail(key, f"no material named {validate.describe(raw)} (materials: {known})")
        return named[raw]
    return parse_material(ctx, key, raw)


def parse_materials(ctx: Reader, mats: Any) -> dict[str, Material]:
    """`materials`: name -> material, for objects to refer to."""
    if not isinstance(mats, dict):
        raise ctx.fail("materials", "expected a mapping name -> material")
    named: dict[str, Material] = {}
    for name, raw in mats.items():
        if not isinstance(name, str) or not 0 < len(name) <= 64 or not name.isprintable():
            raise ctx.fail(
                "materials", f"{validate.describe(name)} is not a material name (text, 1 to 64 printable characters)"
            )
        named[name] = parse_material(ctx, f"materials.{name}", raw)
    return named
