"""Dotted-path overrides (``Scene.with_overrides({"vessel.speed": 4.0, "lines[0].segments": 12})``).
"""
import re
from typing import Any


from .errors import _short


def _clean(d):
    """Drop ``None`` values (TOML has no null) recursively."""
    if isinstance(d, dict):
        return {k: _clean(v) for k, v in d.items() if v is not None}
    if isinstance(d, list):
        return [_clean(v) for v in d]
    return d


_TOKEN = re.compile(r"([^.\[\]]+)|\[([^\]]*)\]")


def _split_path(path: str) -> list[str]:
    if not path or path.startswith(".") or path.endswith("."):
        raise ValueError(f"not a dotted path: {path!r}")
    toks = [m.group(1) if m.group(1) is not None else m.group(2) for m in _TOKEN.finditer(path)]
    if not toks or "".join(toks) == "" or any(t == "" for t in toks):
        raise ValueError(f"not a dotted path: {path!r}")
    return [t.strip() for t in toks]


def _list_index(lst: list, tok: str) -> int:
    if re.fullmatch(r"-?\d+", tok):
        i = int(tok)
        if not -len(lst) <= i < len(lst):
            raise IndexError(f"index {i} out of range (list has {len(lst)} entries)")
        return i % len(lst)
    names = [x.get("name") if isinstance(x, dict) else None for x in lst]
    if tok in names:
        return names.index(tok)
    raise KeyError(f"no entry named {tok!r} (names: {', '.join(repr(n) for n in names if n is not None) or 'none'})")


def _set_path(data: dict, path: str, value: Any) -> None:
    toks = _split_path(path)
    cur: Any = data
    for t in toks[:-1]:
        if isinstance(cur, list):
            cur = cur[_list_index(cur, t)]
        elif isinstance(cur, dict):
            if t not in cur or cur[t] is None:
                cur[t] = {}
            elif not isinstance(cur[t], (dict, list)):
                cur[t] = {}
            cur = cur[t]
        else:
            raise TypeError(f"cannot descend into {_short(cur)} at {t!r}")
    last = toks[-1]
    if isinstance(cur, list):
        i = _list_index(cur, last)
        if value is None:
            del cur[i]
        else:
            cur[i] = value
    elif isinstance(cur, dict):
        if value is None:
            cur.pop(last, None)
        else:
            cur[last] = value
    else:
        raise TypeError(f"cannot set {last!r} inside {_short(cur)}")
