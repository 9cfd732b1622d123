"""`implgen cache info|clear`: what the build cache holds, and emptying it.

    implgen cache info    the folder, its entries by kind with their sizes, the total and the size bound
    implgen cache clear   remove every entry (only names of the cache's layout; links are not followed)

Both check the folder as every build does (cachedir: ours, not a link, not writable by group or others) and
refuse it with one line otherwise: `clear` must not delete in a folder someone else may have prepared, and
`info` says why a build would refuse it. Neither creates the folder. The argument list is tiny, so it is read
here rather than through argparse.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from implgen import cachedir
from implgen.compile import cachesize
from implgen.errors import UserError

USAGE = "usage: implgen cache info|clear"
_KIND_ORDER = [*cachesize.KINDS, "old", "writing", "leftover"]
_KIND_NOTE = {
    "lib": "linked libraries",
    "obj": "object files",
    "glue": "shape lists",
    "gen": "generated shapes",
    "spec": "parsed specs",
    "roots_reference": "exact reference roots (never evicted)",
    "old": "left by an earlier implgen",
    "writing": "being written by a build that runs now (left alone)",
    "leftover": "unfinished writes of builds that have ended (removed at the next build)",
}


def _mb(size: int) -> str:
    return f"{size / 1e6:.1f} MB"


def _checked_root() -> Path | None:
    """The cache folder, checked; None when it does not exist yet."""
    root = cachedir.cache_root()
    if not os.path.lexists(root):
        return None
    problem = cachedir.folder_problem(root)
    if problem:
        raise UserError(cachedir.label(root), f"{root} {problem}; refused (see implgen's docs on the build cache)")
    return root


def info() -> int:
    bound = cachedir.max_bytes()
    root = _checked_root()
    where = cachedir.cache_root()
    source = f"${cachedir.ENV}" if os.environ.get(cachedir.ENV) else "default"
    print(f"folder: {where} ({source}){'' if root else ', not created yet'}")
    units = cachesize.inventory(root) if root else []
    for kind in _KIND_ORDER:
        mine = [u for u in units if u.kind == kind]
        if mine:
            size = sum(u.size for u in mine)
            print(f"  {kind:<16} {len(mine):6d} entries {_mb(size):>11}  {_KIND_NOTE[kind]}")
    total = sum(u.size for u in units)
    bound_from = f"${cachedir.MAX_ENV}" if os.environ.get(cachedir.MAX_ENV, "").strip() else "default"
    print(f"total: {len(units)} entries, {_mb(total)}; bound {_mb(bound)} ({bound_from}), least recently used evicted")
    return 0


def clear() -> int:
    root = _checked_root()
    if root is None:
        print(f"implgen: nothing to clear ({cachedir.cache_root()} does not exist)")
        return 0
    removed, failed = cachesize.clear(root)
    print(f"implgen: removed {len(removed)} entries ({_mb(sum(u.size for u in removed))}) from {root}")
    if failed:
        raise UserError(
            cachedir.label(root), f"{len(failed)} entries could not be removed, e.g. {failed[0].path} (read-only?)"
        )
    return 0


SUBCOMMANDS = {
    "info": (
        "The folder, its entries by kind with their sizes, the total and the size bound. It creates nothing, and\n"
        "says why a build would refuse the folder.",
        "what the cache holds, and its bound",
    ),
    "clear": (
        "Remove every entry (only names of the cache's layout; links are removed, not followed). The cache is\n"
        "rebuilt on the next build.",
        "empty it (it is rebuilt on the next render)",
    ),
}

HELP = f"""{USAGE}

The build cache: compiled libraries and objects, generated C and parsed specs (docs/tracer.md,
"Build cache"). Its folder is $IMPLGEN_CACHE, else $XDG_CACHE_HOME/implgen, else ~/.cache/implgen.
Its size bound is $IMPLGEN_CACHE_MAX_MB (default 500); past it, the least recently used entries go.

  info    the folder, its entries by kind with their sizes, the total and the bound
  clear   remove every entry (only names of the cache's layout; links are removed, not followed)

examples:
""" + "\n".join(f"  # {example}\n  implgen cache {word}" for word, (_, example) in SUBCOMMANDS.items())


def _sub_help(word: str) -> str:
    text, example = SUBCOMMANDS[word]
    return f"usage: implgen cache {word}\n\n{text}\n\nexamples:\n  # {example}\n  implgen cache {word}"


def main(argv: Sequence[str]) -> int:
    args = list(argv)
    if args in (["-h"], ["--help"]):
        print(HELP)
        return 0
    if len(args) == 2 and args[0] in SUBCOMMANDS and args[1] in ("-h", "--help"):
        print(_sub_help(args[0]))
        return 0
    if len(args) != 1 or args[0] not in SUBCOMMANDS:
        raise UserError("cache", f"choose one of: info, clear ({USAGE})")
    return info() if args[0] == "info" else clear()
