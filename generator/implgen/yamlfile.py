"""Reading a small YAML file safely: one-line errors, bounded size, aliases counted as expanded.

Shape specs and scenes are read here. `safe_load` rules (no Python tags), duplicate keys refused, YAML 1.2
floats (`1e-3`) read as numbers, at most MAX_FILE_BYTES read whatever `stat` says, and a document refused
when it holds more than MAX_YAML_NODES values once its aliases are expanded (an alias bomb) or an alias that
contains itself -- counted on the composed node graph, before anything is built from it.
"""

from __future__ import annotations

import os
import re
import stat
import sys
from pathlib import Path
from typing import Any

import yaml

from implgen.errors import UserError

MAX_FILE_BYTES = 1 << 20
MAX_YAML_NODES = 100_000  # scalars, lists and mappings of a document with every alias expanded

_BaseLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's parser when PyYAML has it: 20x faster


class _UniqueKeyLoader(_BaseLoader):  # type: ignore[misc,valid-type]
    """safe_load, but a key given twice is an error rather than silently the last one. Merge keys
    (`<<: *defaults`) work as in YAML: the mapping's own keys override the merged ones."""


def _construct_mapping(loader: _UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False) -> dict:
    seen = set()
    for key_node, _ in node.value:
        if key_node.tag == "tag:yaml.org,2002:merge":  # `<<: *defaults`: merged keys may be overridden
            continue
        key = loader.construct_object(key_node, deep=deep)
        if isinstance(key, (str, int, float)) and key in seen:
            raise yaml.constructor.ConstructorError(None, None, f"duplicate key {key!r}", key_node.start_mark)
        if isinstance(key, (str, int, float)):
            seen.add(key)
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)
# YAML 1.1 (PyYAML) reads `1e-3` and `2E6` as text: it wants a dot and a signed exponent. Read them as
# numbers, as YAML 1.2 and every user do.
_UniqueKeyLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


def _expanded_size(root: yaml.Node, limit: int) -> int:
    """Nodes in the document with every alias expanded, counted without expanding anything: a node reached
    through several aliases is counted once per path. Raises ValueError past `limit` or on a cycle."""
    sizes: dict[int, int] = {}
    open_nodes: set[int] = set()

    def size(node: yaml.Node) -> int:
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in open_nodes:
            raise ValueError("an alias refers to a node that contains it (a cycle)")
        open_nodes.add(key)
        total = 1
        if isinstance(node, yaml.SequenceNode):
            total += sum(size(child) for child in node.value)
        elif isinstance(node, yaml.MappingNode):
            total += sum(size(k) + size(v) for k, v in node.value)
        open_nodes.discard(key)
        if total > limit:
            raise ValueError(f"more than {limit} values once its aliases are expanded")
        sizes[key] = total
        return total

    return size(root)


def _int_digits() -> int:
    return getattr(sys, "get_int_max_str_digits", lambda: 4300)()


def _file_kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a fifo"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "not a regular file"


def read_yaml(path: Path, what: str = "shape spec") -> Any:
    """Read a small YAML file safely; any failure is a one-line UserError naming the file. `what` says which
    kind of file was expected; nothing of a file's text is echoed unless it parsed as YAML."""
    try:
        info = os.stat(path)
    except OSError as err:
        reason = "not found" if isinstance(err, FileNotFoundError) else f"cannot read: {err.strerror or err}"
        raise UserError(path, f"{reason} (expected a {what} file)") from None
    if not stat.S_ISREG(info.st_mode):
        raise UserError(path, f"is {_file_kind(info.st_mode)}, not a {what} file")
    if info.st_size > MAX_FILE_BYTES:
        raise UserError(path, f"file larger than {MAX_FILE_BYTES} bytes (expected a {what} file)")
    try:
        with open(path, "rb") as fh:
            raw = fh.read(MAX_FILE_BYTES + 1)  # stat can under-report (/proc): never read more
    except OSError as err:
        raise UserError(path, f"cannot read: {err.strerror or err}") from None
    if len(raw) > MAX_FILE_BYTES:
        raise UserError(path, f"file larger than {MAX_FILE_BYTES} bytes (expected a {what} file)")
    try:
        if b"\0" in raw:
            raise UnicodeDecodeError("utf-8", raw, 0, 1, "NUL byte")
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise UserError(path, f"is not a text file (expected a {what}: YAML text)") from None
    loader = _UniqueKeyLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded_size(node, MAX_YAML_NODES)
        return loader.construct_document(node)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise UserError(path, f"invalid YAML{where}: {problem[:80]} (expected a {what} file)") from None
    except ValueError as err:
        if "integer string conversion" in str(err):  # Python's own limit, worded for Python programmers
            raise UserError(path, f"refused YAML: a number is written with more than {_int_digits()} digits") from None
        raise UserError(path, f"refused YAML: {err}") from None
    except RecursionError:
        raise UserError(path, "invalid YAML: nested too deeply") from None
    finally:
        loader.dispose()
