"""JSON that a reader can bound before it parses: nesting depth and size checked up front.

Python's ``json`` recurses once per nesting level, so a few kilobytes of ``[[[[…`` end in a
``RecursionError`` (or exhaust the stack) instead of an error that names the file. :func:`loads`
first strips the strings, counts the brackets' depth with one cumulative sum, and refuses text
nested deeper than ``max_depth`` or longer than ``max_chars``, naming the file; then it parses.
Every metadata reader of the project calls it (acquired scans' sidecars and TIFF descriptions,
and any other reader that wants the same bound).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from ..validate import InputError

MAX_DEPTH = 64  # metadata objects nest a few levels; 64 is far beyond any real one
MAX_CHARS = 16 << 20  # 16 Mi characters: metadata, never samples
_STRINGS = re.compile(r'"(?:[^"\\]|\\.)*"')  # a JSON string, escapes included


def depth(text: str) -> int:
    """The deepest nesting of arrays and objects in ``text`` (brackets inside strings do not
    count)."""
    skeleton = np.frombuffer(_STRINGS.sub('""', text).encode("utf-8", "replace"), np.uint8)
    steps = np.isin(skeleton, (ord("["), ord("{"))).astype(np.int64) - np.isin(
        skeleton, (ord("]"), ord("}"))
    )
    return int(np.cumsum(steps).max(initial=0))


def loads(
    text: str, name, *, error=InputError, max_depth: int = MAX_DEPTH, max_chars: int = MAX_CHARS
):
    """The value of the JSON ``text`` from ``name`` (a file, or a file and the place in it);
    ``error`` (an :class:`InputError` class) naming ``name`` when the text is longer than
    ``max_chars``, nested deeper than ``max_depth`` or not JSON."""
    if len(text) > max_chars:
        raise error(
            f"{name}: {len(text)} characters of JSON metadata, more than the "
            f"{max_chars} a reader takes"
        )
    deepest = depth(text)
    if deepest > max_depth:
        raise error(
            f"{name}: JSON nested {deepest} levels deep; metadata may nest at most {max_depth}"
        )
    try:
        return json.loads(text)
    except (ValueError, RecursionError) as e:
        raise error(f"{name}: not valid JSON ({e})"[:400]) from None


def load(path, *, error=InputError, max_depth: int = MAX_DEPTH, max_chars: int = MAX_CHARS):
    """:func:`loads` of the UTF-8 file at ``path``, its size checked before it is read."""
    path = Path(path)
    if not path.is_file():  # a FIFO or a device would block or never end
        raise error(f"{path}: not a regular file")
    try:
        size = path.stat().st_size
        if size > 4 * max_chars:  # UTF-8 takes at most 4 bytes a character
            raise error(f"{path}: {size} bytes of JSON metadata, more than a reader takes")
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise error(f"{path}: not UTF-8 text ({e})") from None
    except OSError as e:
        raise error(f"{path}: cannot be read ({e.strerror or e})") from None
    return loads(text, path, error=error, max_depth=max_depth, max_chars=max_chars)
