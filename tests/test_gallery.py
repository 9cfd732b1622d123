"""The gallery (implgen.spec.gallery, docs/surfaces.md): at least 20 surfaces, shipped as package data, each
loads and renders a picture that shows the surface; and the spec keys it uses (title, reference, ranges)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from implgen.errors import UserError
from implgen.resources import gallery_dir
from implgen.scene.preview import BACKGROUND, frame, preview_scene
from implgen.scene.render import render
from implgen.spec import gallery
from implgen.spec.entry import parse_spec
from implgen.spec.entry import parse_spec as cached_parse_spec
from implgen.spec.parse import MAX_DEGREE

ROOT = Path(__file__).resolve().parent.parent
ENTRIES = gallery.entries()


def test_the_gallery_lists_at_least_twenty_surfaces_and_each_loads():
    assert len(ENTRIES) >= 20
    assert len({e.name for e in ENTRIES}) == len(ENTRIES)
    for e in ENTRIES:
        spec = e.load()
        assert spec.name == e.name == e.path.stem
        assert e.title and e.description and e.reference, e.name
        assert spec.title == e.title and spec.reference == e.reference and spec.description == e.description
        assert 1 <= spec.degree <= MAX_DEGREE
        assert "\n" not in e.description
        assert e.text.startswith(f"name: {e.name}\n")
        for key, (lo, hi) in spec.ranges.items():
            assert lo <= spec.params[key] <= hi


def test_the_gallery_is_package_data_one_copy_of_examples_shapes():
    """Installed, the specs come from the package (implgen/gallery/), the same files as examples/shapes/."""
    folder = gallery_dir()
    assert folder.parent.name == "implgen" and folder.name == "gallery"
    shipped = {p.name: p.read_bytes() for p in folder.glob("*.yaml")}
    tree = {p.name: p.read_bytes() for p in (ROOT / "examples" / "shapes").glob("*.yaml")}
    assert shipped == tree
    assert gallery.entry("kummer").title == "Kummer quartic"
    assert set(gallery.entry("kummer").as_dict()) == {"name", "title", "description", "reference"}
    with pytest.raises(KeyError):
        gallery.entry("no_such_surface")


def test_a_spec_without_a_reference_is_not_in_the_gallery(tmp_path):
    (tmp_path / "plain.yaml").write_text("name: plain\nequation: x^2 + y^2 + z^2 - 1\n")
    (tmp_path / "famous.yaml").write_text("name: famous\nreference: someone (1900)\nequation: x^2 + y^2 - z^2\n")
    assert [e.name for e in gallery.entries(tmp_path)] == ["famous"]
    assert gallery.entries(tmp_path)[0].title == "famous"  # no title: the name
    (tmp_path / "bad.yaml").write_text("reference: x\nequation: x\n")
    with pytest.raises(UserError, match="bad.yaml: a gallery spec needs a name"):
        gallery.entries(tmp_path)


@pytest.mark.parametrize("e", ENTRIES, ids=[e.name for e in ENTRIES])
def test_every_gallery_surface_renders(e):
    """64x48, one sample: the surface covers part of the picture, and is shaded (not one flat colour)."""
    image = render(preview_scene(e.load_framed(), 64, 48), threads=1)
    background = np.all(np.abs(image - np.asarray(BACKGROUND, dtype=np.float32)) < 1e-6, axis=2)
    surface = image[~background]
    assert 0.03 < len(surface) / background.size < 0.98, e.name
    luminance = surface @ np.array([0.2126, 0.7152, 0.0722])
    assert luminance.std() > 0.02, e.name
    assert len(np.unique(np.round(surface, 3), axis=0)) > 20, e.name


def test_an_open_spec_is_framed_by_a_box_for_its_picture():
    barth = gallery.entry("barth6")
    assert barth.load().box() is None
    assert barth.load_framed().box() == [-2.0, -2.0, -2.0, 2.0, 2.0, 2.0]


def test_a_preview_frames_the_box_and_refuses_a_spec_without_one():
    """preview_scene frames the spec's box (Barth's sextic: the framed one, centre 0, radius sqrt(3) * 2); a spec
    left open has nothing to frame and is a ValueError, not a picture of something else."""
    barth = gallery.entry("barth6")
    centre, radius = frame(barth.load_framed())
    assert np.array_equal(centre, np.zeros(3)) and radius == pytest.approx(2.0 * np.sqrt(3.0), rel=1e-15)
    scene = preview_scene(barth.load_framed(), 64, 48)
    (leaf,) = scene.leaves()
    assert leaf.spec.box() == [-2.0, -2.0, -2.0, 2.0, 2.0, 2.0]  # the shape itself, with no clip beside it
    with pytest.raises(ValueError, match="barth6 has no whole box"):
        preview_scene(barth.load(), 64, 48)


SPEC = {"name": "s", "equation": "x^2 + y^2 + z^2 - a^2", "params": {"a": 1.0}}


@pytest.mark.parametrize(
    "extra, message",
    [
        ({"title": 3}, "title: must be text"),
        ({"title": "t" * 81}, "title: longer than 80 characters"),
        ({"reference": ["a"]}, "reference: must be text"),
        ({"ranges": [1, 2]}, "ranges: must be a mapping"),
        ({"ranges": {"b": [0, 1]}}, "ranges: 'b' is not a declared param"),
        ({"ranges": {"a": [0, 1, 2]}}, r"ranges.a: must be a pair \[low, high\]"),
        ({"ranges": {"a": [2, 0.5]}}, "ranges.a: low must be below high"),
        ({"ranges": {"a": [2, 3]}}, "ranges.a: does not hold the default 1"),
        ({"ranges": {"a": ["x", 3]}}, "ranges.a:"),
        ({"ranges": {"a": [0.5, 1e300]}}, "ranges.a"),  # a^2 overflows at the range's end
    ],
)
def test_bad_title_reference_and_ranges_are_one_line(extra, message):
    with pytest.raises(UserError, match=message) as err:
        parse_spec({**SPEC, **extra}, "t.yaml")
    assert "\n" not in str(err.value) and str(err.value).startswith("t.yaml: ")


def test_title_reference_and_ranges_survive_the_spec_cache():
    data = {**SPEC, "title": "A  ball", "reference": "Euclid, Elements XII", "ranges": {"a": [0.5, 2]}}
    first, again = (
        cached_parse_spec(dict(data), "t.yaml", cache=True),
        cached_parse_spec(dict(data), "t.yaml", cache=True),
    )
    assert again.symbolic_part.deferred
    for spec in (first, again):
        assert (spec.title, spec.reference, spec.ranges) == ("A ball", "Euclid, Elements XII", {"a": (0.5, 2.0)})
    assert first.specialise({"a": 1.5}).ranges == {}  # a folded param has no slider
