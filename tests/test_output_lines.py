"""Success lines show the output path as error lines do: anything unprintable escaped.

An `-o` path holding a terminal escape or a newline was printed raw by the line that says where the files went,
while an error line about the same path showed it escaped (errors.UserError). Both go through one function now
(errors.printable): the path's bytes are all there, as \\xNN, and the line stays one line of plain text.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from implgen.errors import UserError, printable
from implgen_proc import implgen

ROOT = Path(__file__).resolve().parent.parent
SPHERE = ROOT / "examples" / "shapes" / "sphere.yaml"
SCENE = ROOT / "examples" / "scenes" / "glassware.yaml"
NAME = "out\x1b[31mred\x07\nx"  # an escape that colours a terminal, a bell, a line break
SHOWN = "out\\x1b[31mred\\x07\\x0ax"

COMMANDS = {
    "generate": lambda o: [SPHERE, "-o", o],
    "share": lambda o: ["share", SPHERE, "-o", f"{o}.html"],
    "mesh": lambda o: ["mesh", SPHERE, "--cells", "8", "-o", f"{o}.stl"],
    "render": lambda o: ["render", SCENE, "-o", f"{o}.png", "-q", "--width", "4", "--height", "3"],
}


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_the_output_path_is_shown_escaped_in_the_success_line(tmp_path, command):
    ran = implgen(*COMMANDS[command](tmp_path / NAME))
    assert ran.code == 0, ran.err
    said = ran.out + ran.err
    assert f"{tmp_path}/{SHOWN}" in said
    assert "\x1b" not in said and "\x07" not in said
    assert [p.name.startswith(NAME) for p in tmp_path.iterdir()] == [True]  # the file has the name as given


def test_success_and_error_lines_show_a_path_alike():
    assert printable(NAME) == SHOWN
    assert str(UserError(f"-o {NAME.replace(chr(10), '')}", "x")) == f"-o {printable(NAME.replace(chr(10), ''))}: x"
