"""A minimal TOML writer for scenes (``Scene.to_toml``): tables, arrays of tables, strings, numbers, lists.
"""
import math
import re





_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(k: str) -> str:
    return k if _BARE.match(k) else _toml_str(k)


def _toml_str(s: str) -> str:
    out = ['"']
    for ch in s:
        o = ord(ch)
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif ch == "\r":
            out.append("\\r")
        elif o < 0x20 or o == 0x7F:
            out.append(f"\\u{o:04X}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
        r = repr(v)
        return r if any(c in r for c in ".en") else r + ".0"
    if isinstance(v, str):
        return _toml_str(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _is_table_array(v) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def _emit_table(d: dict, prefix: str, out: list[str]) -> None:
    simple = {k: v for k, v in d.items() if not isinstance(v, dict) and not _is_table_array(v)}
    small = {k: v for k, v in d.items() if isinstance(v, dict) and len(v) <= 3
             and all(not isinstance(x, (dict, list)) for x in v.values())}
    for k, v in simple.items():
        out.append(f"{_key(k)} = {_toml_value(v)}")
    for k, v in small.items():
        out.append(f"{_key(k)} = {_toml_value(v)}")
    for k, v in d.items():
        if k in simple or k in small:
            continue
        name = f"{prefix}.{_key(k)}" if prefix else _key(k)
        if isinstance(v, dict):
            out.append("")
            out.append(f"[{name}]")
            _emit_table(v, name, out)
        else:
            for item in v:
                out.append("")
                out.append(f"[[{name}]]")
                _emit_table(item, name, out)


def dumps_toml(d: dict) -> str:
    """Serialise a scene dict (nested dicts/lists of scalars) to TOML."""
    out: list[str] = []
    _emit_table(d, "", out)
    return "\n".join(out).lstrip("\n") + "\n"
