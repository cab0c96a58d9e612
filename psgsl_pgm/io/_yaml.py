"""The one safe YAML reader of the project: every YAML file a user hands to psgsl is read here.

On top of :func:`yaml.safe_load` (no arbitrary Python objects) it refuses what ``safe_load`` lets through
silently or reports badly:

* **duplicate keys** in a mapping (``safe_load`` keeps the last one) — the message names the file, the key
  and both lines. Merge keys (``<<: *base``) may still be overridden explicitly, as YAML intends;
* **integers too large for a float** (``10**400`` written out) — they would raise :class:`OverflowError`
  wherever the number is used; refused at load time naming the file and the line. The limit is
  :data:`MAX_INT_DIGITS` characters and ``|x| <= sys.float_info.max`` (≈ 1.8e308);
* **files that are not UTF-8** (UTF-8 with or without byte-order mark, and UTF-16 with a byte-order mark, are
  read) — a :class:`ValueError` naming the file and the offending byte instead of a bare
  :class:`UnicodeDecodeError`;
* **nesting deeper than** :data:`MAX_DEPTH` levels (the parser's time grows with its square);
* **files larger than** :data:`MAX_YAML_BYTES`, directories, unreadable files and malformed YAML — each one :class:`ValueError` naming the file (a missing file is
  :class:`FileNotFoundError`).

Every message is one line that starts with the file name, so the command line can print it as is.

Examples
--------
>>> from psgsl_pgm.io._yaml import load_yaml_text
>>> load_yaml_text("a: 1\\nb: [2, 3]\\n")
{'a': 1, 'b': [2, 3]}
>>> load_yaml_text("a: 1\\na: 2\\n", source="x.yaml")
Traceback (most recent call last):
...
ValueError: x.yaml: duplicate key 'a' at line 2 (first at line 1); a key may appear only once in a mapping
"""

from __future__ import annotations

import codecs
import os
import sys
from pathlib import Path

import yaml

__all__ = ["MAX_DEPTH", "MAX_INT_DIGITS", "MAX_YAML_BYTES", "load_yaml", "load_yaml_mapping", "load_yaml_text"]

#: Largest YAML file read, bytes (64 MiB: map and world descriptions are a few kB; their images are separate).
MAX_YAML_BYTES = 64 * 2**20

#: Longest integer literal accepted, characters (a float holds at most 309 decimal digits).
MAX_INT_DIGITS = 400

#: Deepest nesting of lists and mappings accepted. The parser's cost grows with the square of the depth
#: (20 000 nested ``[`` take minutes); real files nest a few levels.
MAX_DEPTH = 100

_FLOAT_MAX = sys.float_info.max
_MERGE_TAG = "tag:yaml.org,2002:merge"


class _Refused(yaml.YAMLError):
    """A construct the project refuses (duplicate key, huge integer); carries a ready one-line message."""


def _line(node) -> int:
    return node.start_mark.line + 1


class _SafeLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses duplicate keys, integers a float cannot hold and deep nesting."""

    _depth = 0

    def compose_node(self, parent, index):
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                mark = self.peek_event().start_mark
                raise _Refused(f"nested deeper than {MAX_DEPTH} levels at line {mark.line + 1}")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            first: dict = {}
            for key_node, _ in node.value:
                if key_node.tag == _MERGE_TAG:
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    seen = key in first
                except TypeError:  # unhashable key: SafeConstructor reports it with its position
                    break
                if seen:
                    raise _Refused(
                        f"duplicate key {key!r} at line {_line(key_node)} (first at line {first[key]}); a key may "
                        "appear only once in a mapping"
                    )
                first[key] = _line(key_node)
        return super().construct_mapping(node, deep=deep)

    def construct_yaml_int(self, node):
        text = self.construct_scalar(node)
        if len(text) > MAX_INT_DIGITS:
            raise _Refused(
                f"integer of {len(text)} characters at line {_line(node)} is too large: numbers must lie within "
                f"±{_FLOAT_MAX:.4g} (the largest float)"
            )
        value = super().construct_yaml_int(node)
        if abs(value) > _FLOAT_MAX:
            raise _Refused(
                f"integer {text[:12]}… at line {_line(node)} is too large: numbers must lie within ±{_FLOAT_MAX:.4g} "
                "(the largest float)"
            )
        return value


_SafeLoader.add_constructor("tag:yaml.org,2002:int", _SafeLoader.construct_yaml_int)


def _one_line(exc: yaml.YAMLError) -> str:
    """A YAML error as one line: problem, context and position."""
    if isinstance(exc, _Refused):
        return str(exc)
    if isinstance(exc, yaml.MarkedYAMLError):
        parts = [p for p in (exc.context, exc.problem) if p]
        mark = exc.problem_mark or exc.context_mark
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        return f"not valid YAML: {'; '.join(parts) or type(exc).__name__}{where}"
    return "not valid YAML: " + " ".join(str(exc).split())


def load_yaml_text(text: str, *, source: str = "<string>"):
    """Parse one YAML document from ``text`` with the project's safe loader.

    Parameters
    ----------
    text : str
        The YAML text.
    source : str, keyword-only
        What to call the text in error messages (a file name).

    Returns
    -------
    object
        The document (dict, list, str, int, float, bool, None, ...); ``None`` for an empty document.

    Raises
    ------
    TypeError
        ``text`` is not a str.
    ValueError
        Malformed YAML, a duplicate key, an integer too large for a float, nesting too deep — the message
        starts with ``source`` and names the line.
    """
    if not isinstance(text, str):
        raise TypeError(f"YAML text must be a str, got {type(text).__name__}")
    try:
        return yaml.load(text, Loader=_SafeLoader)  # noqa: S506 - _SafeLoader derives from yaml.SafeLoader
    except yaml.YAMLError as exc:
        raise ValueError(f"{source}: {_one_line(exc)}") from None
    except RecursionError:
        raise ValueError(f"{source}: not valid YAML: nested too deeply for the parser") from None


def _decode(data: bytes, source: str) -> str:
    if data.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)) and not data.startswith(codecs.BOM_UTF32_LE):
        encoding = "utf-16"
    else:
        encoding = "utf-8-sig"
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise ValueError(
            f"{source}: not {encoding.upper().replace('-SIG', '')} text: byte 0x{data[exc.start]:02x} at offset "
            f"{exc.start} (line {line}) cannot be decoded; save the file as UTF-8"
        ) from None


def load_yaml(path):
    """Read one YAML document from the file ``path`` with the project's safe loader.

    Parameters
    ----------
    path : str or os.PathLike
        The file. UTF-8 (optionally with a byte-order mark) or UTF-16 with a byte-order mark; at most
        :data:`MAX_YAML_BYTES` bytes.

    Returns
    -------
    object
        The document; ``None`` for an empty file.

    Raises
    ------
    FileNotFoundError
        No such file.
    TypeError
        ``path`` is not a path.
    ValueError
        A directory, an unreadable or too large file, bytes that are not UTF-8, malformed YAML, a duplicate
        key, an integer too large for a float — the message starts with the file name.
    """
    if isinstance(path, bool) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a file path (str or os.PathLike), got {type(path).__name__} {path!r}")
    p = Path(path)
    try:
        if p.is_dir():
            raise ValueError(f"{p}: is a directory, expected a YAML file")
        size = p.stat().st_size
        if size > MAX_YAML_BYTES:
            raise ValueError(f"{p}: {size} bytes is larger than the {MAX_YAML_BYTES} bytes a YAML file may have")
        with open(p, "rb") as fh:
            data = fh.read(MAX_YAML_BYTES + 1)
    except FileNotFoundError:
        raise FileNotFoundError(f"{p}: no such file") from None
    except OSError as exc:
        raise ValueError(f"{p}: cannot read the file ({exc.strerror or type(exc).__name__})") from None
    if len(data) > MAX_YAML_BYTES:  # a file that grew, or a device
        raise ValueError(f"{p}: larger than the {MAX_YAML_BYTES} bytes a YAML file may have")
    return load_yaml_text(_decode(data, str(p)), source=str(p))


def load_yaml_mapping(path) -> tuple[Path, dict]:
    """Read a YAML file whose top level must be a mapping; returns ``(Path(path), mapping)``.

    Raises as :func:`load_yaml`, and :class:`ValueError` naming the file when the top level is not a mapping.
    """
    data = load_yaml(path)
    p = Path(path)
    if not isinstance(data, dict):
        raise ValueError(f"{p}: expected a YAML mapping at the top level, got {type(data).__name__}")
    return p, data
