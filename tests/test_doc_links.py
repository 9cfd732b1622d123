"""Links in the documentation resolve: every relative link and image in README.md, docs/**/*.md and
bench/README.md points to an existing file, and a `#fragment` to a heading of the target (GitHub's slugs).
The docs pages and README paths that the C runtime and the Python package mention in their comments must
exist too. Plain text parsing only: no network, no Markdown library; runs in well under a second.
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parent.parent

# Result files that a benchmark script will write but has not written yet. A link to one of these may point
# nowhere for now; everything else must resolve. Take an entry out once its file exists (a test below fails
# until you do). Only bench/results/ files belong here.
PENDING = {}


def doc_files() -> list[Path]:
    files = [ROOT / "README.md", ROOT / "bench" / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    return [f for f in files if f.is_file()]


def source_files() -> list[Path]:
    return sorted([*(ROOT / "runtime_c").rglob("*.[ch]"), *(ROOT / "generator").rglob("*.py")])


def rel(path: Path) -> str:
    return path.resolve().relative_to(ROOT).as_posix()


# --- Markdown, as much of it as links need -------------------------------------------------------------------

FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")


def strip_code(text: str) -> str:
    """Blank out fenced code blocks and inline code spans (links inside them are not links), keeping lines."""
    out, fence = [], None
    for line in text.splitlines():
        m = FENCE.match(line)
        if fence:
            if m and m.group(1)[0] == fence[0] and len(m.group(1)) >= len(fence):
                fence = None
            out.append("")
        elif m:
            fence = m.group(1)
            out.append("")
        else:
            out.append(re.sub(r"(`+)(.+?)\1", lambda c: " " * len(c.group(0)), line))
    return "\n".join(out)


INLINE_LINK = re.compile(r"\]\(\s*(<[^>]*>|[^)\s]+)(?:\s+(?:\"[^\"]*\"|'[^']*'))?\s*\)")
REF_DEF = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)", re.M)
HTML_LINK = re.compile(r"<(?:a|img)\b[^>]*?\b(?:href|src)\s*=\s*[\"']([^\"']+)[\"']", re.I)


def links(text: str) -> list[str]:
    text = strip_code(text)
    found = INLINE_LINK.findall(text) + REF_DEF.findall(text) + HTML_LINK.findall(text)
    return [t[1:-1] if t.startswith("<") else t for t in found]


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: the text as rendered, lower case, punctuation dropped, spaces to '-'."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links and images: their text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML
    text = text.replace("`", "")
    text = re.sub(r"(\*{1,3}|_{1,3})(\S(?:.*?\S)?)\1", r"\2", text)  # emphasis
    text = text.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


@cache
def anchors(path: Path) -> frozenset[str]:
    """Every anchor GitHub makes in this Markdown file: heading slugs (repeats get -1, -2, ...) and HTML ids."""
    raw = path.read_text(encoding="utf-8")
    text = strip_code(raw)
    seen: dict[str, int] = {}
    out: set[str] = set()
    lines = text.splitlines()
    for i, line in enumerate(lines):
        m = re.match(r"^ {0,3}#{1,6}(?:[ \t]+(.*?))?[ \t]*$", line)
        heading = None
        if m:
            heading = re.sub(r"[ \t]+#+$", "", m.group(1) or "")
        elif (
            i + 1 < len(lines)
            and line.strip()
            and re.match(r"^ {0,3}(=+|-+)[ \t]*$", lines[i + 1])
            and not re.match(r"^ {0,3}([-*+]|\d+[.)])\s", line)
            and "|" not in line
        ):
            heading = line.strip()  # setext heading
        if heading is None:
            continue
        base = slug(heading)
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    out.update(re.findall(r"<a\b[^>]*?\b(?:id|name)\s*=\s*[\"']([^\"']+)[\"']", raw, re.I))
    return frozenset(out)


def check_target(source: Path, target: str) -> str | None:
    """None if `target` (as written in `source`) resolves, else why not."""
    if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:|^//", target):
        return None  # http:, mailto: ...: not checked here
    path_part, _, fragment = target.partition("#")
    path_part = unquote(path_part)
    dest = (source.parent / path_part).resolve() if path_part else source.resolve()
    try:
        where = dest.relative_to(ROOT).as_posix()
    except ValueError:
        return f"{target}: leaves the repository"
    if not dest.exists():
        if where in PENDING:
            return None
        return f"{target}: no such file ({where})"
    if fragment and dest.is_file() and dest.suffix.lower() == ".md":
        if unquote(fragment).lower() not in anchors(dest):
            return f"{target}: no heading #{fragment} in {where}"
    return None


# --- the tests ---------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("doc", doc_files(), ids=rel)
def test_every_link_in_the_docs_resolves(doc: Path) -> None:
    problems = [p for t in links(doc.read_text(encoding="utf-8")) if (p := check_target(doc, t))]
    assert not problems, f"{rel(doc)}: broken links:\n  " + "\n  ".join(problems)


DOC_MENTION = re.compile(r"(?<![\w./-])((?:docs/[\w./-]*?\.md|README\.md)(?:#[\w-]+)?)")


def test_docs_named_in_the_sources_exist() -> None:
    problems = []
    for src in source_files():
        for target in DOC_MENTION.findall(src.read_text(encoding="utf-8", errors="replace")):
            if p := check_target(ROOT / "README.md", target):  # paths in sources are from the repository root
                problems.append(f"{rel(src)}: {p}")
    assert not problems, "sources name missing docs:\n  " + "\n  ".join(problems)


def test_readme_links_every_docs_page() -> None:
    linked = {(ROOT / t.partition("#")[0]).resolve() for t in links((ROOT / "README.md").read_text("utf-8"))}
    missing = [rel(p) for p in sorted((ROOT / "docs").glob("*.md")) if p.resolve() not in linked]
    assert not missing, f"README.md does not link these docs pages: {missing}"


def test_pending_results_are_still_pending() -> None:
    """PENDING is only for bench/results/ files not written yet; once one exists, its entry must go."""
    wrong = sorted(p for p in PENDING if not p.startswith("bench/results/"))
    written = sorted(p for p in PENDING if (ROOT / p).exists())
    assert not wrong, f"PENDING may only hold bench/results/ files: {wrong}"
    assert not written, f"these now exist; take them out of PENDING in {rel(Path(__file__))}: {written}"


# --- the checker checks itself -------------------------------------------------------------------------------------


def test_slugs_follow_github() -> None:
    assert slug("Ray level: clip and shift") == "ray-level-clip-and-shift"
    assert slug("The `implgen bench` commands") == "the-implgen-bench-commands"
    assert slug("Side by side with POV-Ray, and how cost grows") == "side-by-side-with-pov-ray-and-how-cost-grows"
    assert slug("**Bold** and [a link](x.md)") == "bold-and-a-link"
    assert slug("What `implgen render` does") == "what-implgen-render-does"


def test_the_checker_finds_broken_links() -> None:
    doc = ROOT / "docs" / "README.md"
    assert check_target(doc, "formats.md") is None
    assert check_target(doc, "formats.md#ranges") is None
    assert check_target(doc, "formats.md#no-such-heading") is not None
    assert check_target(doc, "no_such_page.md") is not None
    assert check_target(doc, "https://example.org/x") is None
    assert check_target(doc, "#implgen-documentation") is None
    text = "[a](one.md) ![b](img/two.png) `[c](not-a-link.md)`\n```\n[d](neither.md)\n```\n[e]: three.md\n"
    assert links(text) == ["one.md", "img/two.png", "three.md"]
