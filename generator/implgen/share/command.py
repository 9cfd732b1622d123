"""`implgen share SPEC.yaml -o page.html [--param NAME=VALUE ...] [--range NAME=LO:HI ...] [--clip KIND]
[--clip-size S]`, `implgen share SCENE.yaml -o page.html` (the whole scene, share/scenepage.py), or
`implgen share SCENE.yaml --object NAME -o page.html`: one HTML file that draws the shape or the scene in any
WebGL2 browser, from disk, with no server and no network (docs/share.md).

The output path is checked first, then the options against the shape; the page is made in memory and written
under a temporary name, then renamed: bad input leaves nothing behind.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

from implgen import validate
from implgen.args import ArgumentParser
from implgen.errors import UserError, printable
from implgen.outputs import atomic_write, check_output_file
from implgen.share.page import CLIPS, Look, Slider, framing, render_page, slider
from implgen.spec.entry import parse_spec
from implgen.spec.model import Spec
from implgen.spec.paramrange import param_ranges
from implgen.spec.paramvalues import named_items
from implgen.yamlfile import read_yaml

SUFFIXES = (".html", ".htm")
EXAMPLES = (
    ("the torus as a page to send", "implgen share examples/shapes/torus_y.yaml -o torus.html"),
    (
        "starting from other param values, b's slider from 0.05 to 0.5",
        "implgen share examples/shapes/torus_y.yaml --param b=0.4 --range b=0.05:0.5 -o torus.html",
    ),
    (
        "Barth's sextic (unbounded) in a box",
        "implgen share examples/shapes/barth6.yaml --clip box --clip-size 1.5 -o barth.html",
    ),
    ("a whole scene: glass, CSG, shadows", "implgen share examples/scenes/glassware.yaml -o glassware.html"),
    ("one object of a scene", "implgen share examples/scenes/torus_shadow.yaml --object torus_y -o torus.html"),
)


def _pairs(option: str, items: list[str], spec: Spec) -> dict[str, str]:
    return named_items(option, items, spec.name, spec.params)


def _num(label: str, text: str) -> float:
    return validate.number(label, "", text.strip(), text_ok=True)


def sliders(
    spec: Spec, params: list[str], ranges: list[str], source: str, start: dict[str, float] | None = None
) -> list[Slider]:
    """The params' starting values (`start`, a scene object's, else the spec's defaults, then the options) and
    slider ranges (--range, else the spec's `ranges`, else the value +- max(1, |value|)); the values checked
    against the shape."""
    given = {k: _num(f"--param {k}={v}", v) for k, v in _pairs("--param", params, spec).items()}
    values = {**spec.params, **(start or {}), **given}
    if given:
        spec.check_values(values, source, "--param")
    out = []
    spans = _pairs("--range", ranges, spec)
    for name, value in values.items():
        if name in spans:
            label = f"--range {name}={spans[name]}"
            lo_text, colon, hi_text = spans[name].partition(":")
            if not colon:
                raise UserError(label, "expected NAME=LOW:HIGH")
            lo, hi = _num(label, lo_text), _num(label, hi_text)
            if not lo < hi:
                raise UserError(label, f"LOW must be below HIGH (got {lo:g} and {hi:g})")
            if not lo <= value <= hi:
                raise UserError(label, f"the range does not hold {name}'s value {value:g}")
        else:
            out.append(slider(name, value, param_ranges(spec)))  # the spec's own, else the viewer's rule
            continue
        out.append(Slider(name, value, lo, hi))
    return out


def _scene_object(path: Path, name: str) -> tuple[Spec, dict[str, float], Look]:
    """The first object of the scene whose shape is called `name`: its spec, its params, its colours."""
    from implgen.scene.load import load_scene

    scene = load_scene(path)
    leaves = scene.leaves()
    names = list(dict.fromkeys(leaf.spec.name for leaf in leaves))
    for leaf in leaves:
        if leaf.spec.name == name:
            look = Look(background=tuple(scene.background))
            if leaf.material is not None:
                m = leaf.material
                look = Look(outside=m.color, inside=m.inside or m.color, background=tuple(scene.background))
            return leaf.spec, dict(leaf.params), look
    raise UserError(f"--object {name[:60]}", f"no shape of that name in {path} (its shapes: {', '.join(names)})")


def _parser() -> ArgumentParser:
    p = ArgumentParser(
        label="share",
        prog="implgen share",
        description="Write one HTML file that draws a shape in any WebGL2 browser, opened from disk: no server, "
        "no network. It holds the shape's GLSL and implgen's GLSL runtime, a slider per param, orbit and zoom, "
        "the outside and inside colours, a clip sphere or box, and marks the pixels single precision could not "
        "decide (docs/share.md).",
        examples=EXAMPLES,
    )
    p.add_argument(
        "file",
        type=Path,
        metavar="SPEC.yaml",
        help="a shape spec, or a scene (the whole scene, or with --object one shape)",
    )
    p.add_argument("-o", "--output", type=Path, required=True, metavar="PAGE.html", help="the page to write")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE", help="a param's starting value")
    p.add_argument(
        "--range",
        action="append",
        default=[],
        metavar="NAME=LOW:HIGH",
        help="a slider's range (default: value +- max(1, |value|))",
    )
    p.add_argument("--clip", choices=CLIPS, default=None, help="the clip the page starts with (default: sphere)")
    p.add_argument("--clip-size", type=str, default=None, metavar="S", help="its radius, or half the box's edge")
    p.add_argument(
        "--cut",
        action="store_true",
        help="start with the solid (f < 0) cut by the clip, its cut face in the inside colour (default: the surface "
        "inside the clip, cut open, as the viewer)",
    )
    p.add_argument("--object", default=None, metavar="NAME", help="for a scene: the shape to share (its first object)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    return p


def main(argv: Sequence[str]) -> int:
    args = _parser().parse_args(list(argv))
    check_output_file(args.output, "-o", SUFFIXES)
    clip_size = None
    if args.clip_size is not None:
        clip_size = validate.number("--clip-size", "", args.clip_size, 1e-6, 1e6, text_ok=True)
    data = read_yaml(args.file, what="spec or scene")
    if isinstance(data, dict) and "objects" in data and args.object is None:
        return _scene_page(args)
    if isinstance(data, dict) and "objects" in data:
        spec, start, look = _scene_object(args.file, args.object)
    else:
        if args.object is not None:
            raise UserError(f"--object {args.object[:60]}", f"{args.file} is a shape spec, not a scene")
        spec = parse_spec(data, str(args.file))
        start, look = None, Look()
    slider_list = sliders(spec, args.param, args.range, str(args.file), start)
    orbit, auto_size = framing(spec, {s.name: s.value for s in slider_list}, clip_size, args.clip or look.clip)
    look = Look(
        clip=args.clip or look.clip,
        clip_size=clip_size if clip_size is not None else auto_size,
        cut=args.cut,
        outside=look.outside,
        inside=look.inside,
        background=look.background,
    )
    html = render_page(spec, slider_list, look, args.file.name, orbit)
    size = _write(args.output, html)
    if not args.quiet:
        print(f"{spec.name:<14} degree {spec.degree:>2}  {size:6.1f} kB -> {printable(str(args.output))}")
    return 0


def _write(path: Path, html: str) -> float:
    """The page written whole (a temporary name renamed into place); its size in kB."""
    data_bytes = html.encode("utf-8")
    try:
        atomic_write(path, lambda fh: fh.write(data_bytes))
    except OSError as err:
        raise UserError(f"-o {path}", f"cannot write: {err.strerror or err}") from None
    return len(data_bytes) / 1024


def _scene_page(args) -> int:
    """The whole scene as a page (share/scenepage.py); the shape's options do not apply."""
    from implgen.scene.load import load_scene
    from implgen.share.scenepage import render_scene_page

    for option, given in (
        ("--param", args.param),
        ("--range", args.range),
        ("--clip", args.clip),
        ("--clip-size", args.clip_size),
        ("--cut", args.cut),
    ):
        if given:
            raise UserError(option, f"applies to a shape; {args.file} is a scene (give --object NAME for one shape)")
    scene = load_scene(args.file)
    size = _write(args.output, render_scene_page(scene, args.file.name))
    if not args.quiet:
        print(
            f"{args.file.name:<14} scene, {len(scene.objects)} objects  {size:6.1f} kB -> {printable(str(args.output))}"
        )
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main(sys.argv[1:]))
