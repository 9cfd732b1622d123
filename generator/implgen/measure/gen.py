"""`implgen bench gen`: how long generation takes, and how big the generated code is, against degree.

Two families per degree n: a dense one, the product of n/2 offset spheres (every monomial present), and a
sparse one, x^n + y^n + z^n = 1. For each: the median wall time of parse + derive + emit (C and Python), and
the operation count of the generated coefficient code. With --compare, also the expanded alternative
(compose in the polynomial ring QQ[o, d][t], then one cse) up to the degree it finishes in reasonable time,
to show why implgen uses the Taylor (series) form. Prints the table and writes it, with the machine, to -o
(default bench/results/gen.md).
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Sequence
from pathlib import Path

import sympy

from implgen.args import ArgumentParser
from implgen.codegen.derive import derive, exact_ray_coefficients
from implgen.codegen.emit import derivation_ops, generate
from implgen.errors import UserError, printable
from implgen.measure.machine import describe, load_average, write_results
from implgen.outputs import check_output_file
from implgen.spec.entry import parse_spec
from implgen.spec.parse import MAX_DEGREE

DEGREES = (2, 4, 6, 8, 12, 16, 20, 24)


def dense_equation(n: int) -> str:
    factors = [f"((x - {0.3 * i:.1f})^2 + (y - {0.1 * i:.1f})^2 + z^2 - 1)" for i in range(n // 2)]
    return " * ".join(factors) + " - 0.01"


def sparse_equation(n: int) -> str:
    return f"x^{n} + y^{n} + z^{n} - 1"


def _time_generation(equation: str, repeats: int) -> tuple[float, int, int]:
    times, ops, degree = [], 0, 0
    for _ in range(repeats):
        start = time.perf_counter()
        spec = parse_spec({"name": "bench", "equation": equation}, "<bench>")
        derivation = derive(spec)
        generate(spec, ("c", "python"), derivation)
        times.append(time.perf_counter() - start)
        ops, degree = derivation_ops(derivation, "coeffs"), spec.degree
    return statistics.median(times), ops, degree


def _expanded_ops(equation: str) -> tuple[float, int]:
    """Op count and time of the alternative: exact expanded coefficients in o, d, then one cse."""
    start = time.perf_counter()
    spec = parse_spec({"name": "bench", "equation": equation}, "<bench>")
    coeffs = [c.as_expr() for c in exact_ray_coefficients(spec)]
    temps, reduced = sympy.cse(coeffs, order="none")
    ops = int(sum(sympy.count_ops(e) for _, e in temps) + sum(sympy.count_ops(e) for e in reduced))
    return time.perf_counter() - start, ops


EXAMPLES = (
    ("the table of bench/results/gen.md", "implgen bench gen"),
    ("a quick run: three degrees, no expanded form", "implgen bench gen --degrees 2 4 8 --compare 0 -o out/gen.md"),
)


def main(argv: Sequence[str]) -> int:
    parser = ArgumentParser(prog="implgen bench gen", description=__doc__.splitlines()[0], examples=EXAMPLES)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--compare",
        type=int,
        default=8,
        metavar="N",
        help="also time the expanded form up to degree N (0 to skip; default 8)",
    )
    parser.add_argument("--degrees", type=int, nargs="*", default=list(DEGREES))
    parser.add_argument("-o", "--output", type=Path, default=Path("bench/results/gen.md"))
    args = parser.parse_args(list(argv))
    if any(not 1 <= n <= MAX_DEGREE for n in args.degrees) or args.repeats < 1:
        raise UserError("bench gen", f"degrees must be within 1..{MAX_DEGREE} and repeats at least 1")
    check_output_file(args.output, "-o", (".md",))
    lines = [
        "# Generation time against degree",
        "",
        f"Written by `implgen bench gen` on {describe()}. Load average before: {load_average()}.",
        "",
        f"Generation time (parse + derive + emit C and Python; median of {args.repeats}) "
        f"and operations in the generated coefficient code. Highest supported degree: {MAX_DEGREE}.",
        "",
    ]
    print("\n".join(lines))
    header = "| degree | dense: time | dense: ops | sparse: time | sparse: ops |"
    if args.compare:
        header += " dense expanded+cse: time | ops |"
    table = [header, "|" + "---|" * (header.count("|") - 1)]
    print("\n".join(table))
    for n in args.degrees:
        dense_t, dense_ops, _ = _time_generation(dense_equation(n), args.repeats)
        sparse_t, sparse_ops, _ = _time_generation(sparse_equation(n), args.repeats)
        row = f"| {n} | {dense_t:.2f} s | {dense_ops} | {sparse_t:.2f} s | {sparse_ops} |"
        if args.compare:
            if n <= args.compare:
                exp_t, exp_ops = _expanded_ops(dense_equation(n))
                row += f" {exp_t:.2f} s | {exp_ops} |"
            else:
                row += " – | – |"
        print(row, flush=True)
        table.append(row)
    write_results(args.output, "\n".join(lines + table) + "\n")
    print(f"wrote {printable(str(args.output))}")
    return 0
