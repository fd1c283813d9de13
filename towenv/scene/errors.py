"""SceneError and the machinery that turns pydantic's validation errors into one message per field (dotted
path, what is allowed, the value given).
"""
from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel, ValidationError
from pydantic_core import PydanticCustomError


_INTERNAL = "internal error while validating the scene"


class SceneError(ValueError):
    """Invalid scene. ``problems`` is a list of ``(dotted_path, message)``; ``str(err)`` lists them all."""

    def __init__(self, problems, source: str | None = None):
        if isinstance(problems, str):
            problems = [("", problems)]
        self.problems: list[tuple[str, str]] = list(problems)
        self.source = source
        lines = [f"{p}: {m}" if p else m for p, m in self.problems]
        prefix = f"{source}: " if source else ""
        if len(lines) == 1:
            msg = prefix + lines[0]
        else:
            msg = f"{prefix}{len(lines)} problems in scene:\n" + "\n".join("  " + x for x in lines)
        super().__init__(msg)

    @classmethod
    def from_validation_error(cls, err: ValidationError, source: str | None = None) -> "SceneError":
        problems: list[tuple[str, str]] = []
        errors = err.errors(include_url=False)
        locs = [tuple(e.get("loc", ())) for e in errors]
        for e in errors:
            loc = tuple(e.get("loc", ()))
            if e.get("type") == "too_short" and any(len(o) > len(loc) and o[:len(loc)] == loc for o in locs):
                continue                   # "0 items after validation": its items already reported
            for item in _convert_error(e):
                if item not in problems:
                    problems.append(item)
        if not problems:
            problems = [("", "invalid scene")]
        return cls(problems, source)


def _short(v: Any, limit: int = 80) -> str:
    try:
        if isinstance(v, float):
            s = repr(v)
        elif isinstance(v, (list, tuple)):
            s = "[" + ", ".join(_short(x, 20) for x in v[:8]) + (", ..." if len(v) > 8 else "") + "]"
        else:
            s = repr(v)
    except Exception:  # pragma: no cover - exotic objects with broken repr
        s = f"<{type(v).__name__}>"
    return s if len(s) <= limit else s[: limit - 3] + "..."


def _join(base: str, part: Any) -> str:
    if isinstance(part, int) and not isinstance(part, bool):
        return f"{base}[{part}]"
    part = str(part)
    if not part:
        return base
    if part.startswith("["):
        return base + part
    return f"{base}.{part}" if base else part


def _loc_path(loc) -> str:
    path = ""
    for p in loc:
        if isinstance(p, str) and p.startswith("@"):
            continue                       # discriminated-union tag, not a field
        path = _join(path, p)
    return path


# union error type -> (key naming the variant, allowed values)
_UNION_ERRORS = {
    "bad_manoeuvre": ("type", ("turn", "speed_change")),
    "bad_excitation": ("type", ("sinusoid", "time_series")),
    "bad_body": ("kind", ("fish", "depressor", "ball", "clump")),
}


def _convert_error(e: dict) -> list[tuple[str, str]]:
    loc = tuple(e.get("loc", ()))
    typ = e.get("type", "")
    ctx = e.get("ctx") or {}
    inp = e.get("input")
    path = _loc_path(loc)
    got = f" (got {_short(inp)})"
    if typ == "scene_problems":
        return [(_join(path, sub) if sub else path, msg) for sub, msg in ctx.get("problems", [])]
    if typ == "scene_value":
        return [(path, str(ctx.get("msg", "invalid value")) + got)]
    if typ in _UNION_ERRORS:
        key, allowed = _UNION_ERRORS[typ]
        choices = " or ".join(f'"{a}"' for a in allowed)
        if isinstance(inp, Mapping):
            if key in inp:
                return [(_join(path, key), f"must be {choices} (got {_short(inp[key])})")]
            return [(_join(path, key), f"required field missing; must be {choices}")]
        return [(path, f'must be a table with {key} = {choices}{got}')]
    if typ == "bad_top":
        return [(path, 'must be "vessel", {line = "<name>", distance = <m>} or {body = "<name>"}' + got)]
    if typ == "bad_bottom":
        return [(path, 'must be "free" or {body = "<name>"}' + got)]
    if typ == "missing":
        return [(path, "required field missing")]
    if typ == "extra_forbidden":
        allowed = _allowed_fields(loc[:-1])
        hint = f" (allowed: {', '.join(allowed)})" if allowed else ""
        return [(path, f"unknown field{hint}")]
    if typ in ("model_type", "model_attributes_type", "dict_type"):
        return [(path, "must be a table" + got)]
    if typ in ("tuple_type", "list_type", "iterable_type"):
        return [(path, "must be a list" + got)]
    if typ == "too_short":
        n = ctx.get("min_length", 1)
        return [(path, f"must have at least {n} entr{'y' if n == 1 else 'ies'}" + got)]
    if typ == "string_type":
        return [(path, "must be a string" + got)]
    msg = str(e.get("msg", "invalid value"))
    for prefix in ("Value error, ", "Assertion failed, "):
        if msg.startswith(prefix):
            msg = msg[len(prefix):]
    if msg.startswith("Input should be "):
        msg = "must be " + msg[len("Input should be "):]
    return [(path, msg + got)]


def _model_classes(ann) -> list[type]:
    """BaseModel subclasses mentioned in a type annotation."""
    out: list[type] = []
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return [ann]
    for a in getattr(ann, "__args__", ()) or ():
        out += _model_classes(a)
    origin = getattr(ann, "__origin__", None)
    if origin is not None and origin is not ann:
        out += [c for c in _model_classes(origin) if c not in out]
    return out


def _allowed_fields(loc) -> list[str]:
    """Field names of the model at ``loc`` (used to list allowed names for an unknown field)."""
    try:
        cls: type | None = Scene
        for p in loc:
            if isinstance(p, int):
                continue
            if isinstance(p, str) and p.startswith("@"):
                cls = _TAG_CLASSES.get(p)
                continue
            if cls is None or p not in cls.model_fields:
                return []
            cands = _model_classes(cls.model_fields[p].annotation)
            cls = cands[0] if len(cands) == 1 else None
        return list(cls.model_fields) if cls is not None else []
    except Exception:  # pragma: no cover - defensive: never fail while reporting an error
        return []


def _problems(*items: tuple[str, str]):
    """Raise a validation error carrying several ``(sub_path, message)`` problems."""
    items = [(str(p), str(m)) for p, m in items]
    raise PydanticCustomError("scene_problems", "{summary}",
                              {"summary": "; ".join(f"{p}: {m}" for p, m in items), "problems": items})


def _value_error(msg: str):
    raise PydanticCustomError("scene_value", "{msg}", {"msg": msg})


from .schema import Scene, _TAG_CLASSES  # noqa: E402  (circular: used inside functions only)
