"""`implgen SPEC.yaml [SPEC.yaml ...] --lang c|python|glsl|all [-o DIR]`: validate, derive, emit, write.

Every spec is read and every file produced in memory before anything is written, so bad input leaves the
output folder untouched.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from implgen.args import ArgumentParser
from implgen.codegen.backends import LANGS
from implgen.codegen.emit import generate
from implgen.errors import UserError, printable
from implgen.outputs import check_output_folder, write_text_files
from implgen.spec.entry import load_spec

EXAMPLES = (
    ("the torus as C (torus_z.h, torus_z.c) into out/", "implgen examples/shapes/torus_z.yaml --lang c -o out"),
    ("every example shape, C and Python, into out/generated/", "implgen examples/shapes/*.yaml -o out/generated"),
)


def _parser() -> argparse.ArgumentParser:
    p = ArgumentParser(
        label="command line",
        prog="implgen",
        description="Generate C, Python and GLSL ray intersectors from implicit surface specs. Every spec is checked "
        "and every file made before anything is written. The other commands: implgen --help.",
        examples=EXAMPLES,
    )
    p.add_argument("specs", nargs="+", type=Path, metavar="SPEC.yaml", help="shape specs (docs/formats.md)")
    p.add_argument("--lang", choices=[*LANGS, "all"], default="all", help="what to write (default: all)")
    p.add_argument(
        "-o", "--output", type=Path, default=Path("generated"), metavar="DIR", help="output folder (default: generated)"
    )
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    return p


def main(argv: Sequence[str]) -> int:
    args = _parser().parse_args(list(argv))
    langs = LANGS if args.lang == "all" else (args.lang,)
    check_output_folder(args.output, "-o")
    outputs: dict[str, str] = {}
    summary = []
    for path in args.specs:
        start = time.perf_counter()
        spec = load_spec(path)
        files = generate(spec, langs)
        # Compared without case: on a case-insensitive file system Torus.c and torus.c are one file.
        clash = {f.lower() for f in files} & {f.lower() for f in outputs}
        if clash:
            raise UserError(path, f"writes {sorted(clash)[0]}, which another spec given also writes")
        outputs.update(files)
        summary.append((spec, time.perf_counter() - start, list(files)))
    write_text_files(outputs, args.output)
    if not args.quiet:
        for spec, seconds, names in summary:
            print(
                f"{spec.name:<14} degree {spec.degree:>2}  {seconds * 1000:7.1f} ms  -> "
                + ", ".join(printable(str(args.output / n)) for n in names),
                file=sys.stdout,
            )
    return 0
