"""A benchmark's section of a shared results file: put in place of the old one, the others kept."""

from implgen.measure.machine import write_section

BEGIN, END = "<!-- b: begin -->", "<!-- b: end -->"


def test_a_section_replaces_its_old_self_in_place(tmp_path):
    path = tmp_path / "r.md"
    path.write_text(f"# head\n\n{BEGIN}\nold\n{END}\n\n<!-- other -->\nkept\n")
    write_section(path, BEGIN, END, f"{BEGIN}\nnew\n{END}\n")
    assert path.read_text() == f"# head\n\n{BEGIN}\nnew\n{END}\n\n<!-- other -->\nkept\n"


def test_a_new_section_goes_at_the_end_and_a_missing_file_is_made(tmp_path):
    path = tmp_path / "r.md"
    write_section(path, BEGIN, END, f"{BEGIN}\nfirst\n{END}")
    assert path.read_text() == f"{BEGIN}\nfirst\n{END}\n"
    path.write_text("# head\n")
    write_section(path, BEGIN, END, f"{BEGIN}\nx\n{END}")
    assert path.read_text() == f"# head\n\n{BEGIN}\nx\n{END}\n"
