"""Field types with their allowed ranges and error texts: numbers, integers, 3-vectors, names, choices, segment
counts.
"""
import math
import numbers
from collections.abc import Mapping
from typing import Annotated

from pydantic.functional_serializers import PlainSerializer
from pydantic.functional_validators import PlainValidator

from .errors import _value_error


# Segment count of one line and of the whole scene. Why 5000: the build costs ~0.7 ms per segment (3.5 s at
# 5000, 17.5 s at 20 000, measured on the two-part tow), and segments that short need a tiny Δt for the
# tension iteration to converge (the two-part tow's 20 m secondary diverges from ~150 segments at Δt = 0.02 s,
# transverse Courant number c_T·Δt/l ≈ 2.5; the divergence message names the number) — 5000 is far beyond
# any embedded scene (≤ 100) and the fidelity study.
MAX_SEGMENTS = 5000


_SEGMENTS_WHY = ("longer chains build slowly (~0.7 ms per segment) and segments that short need a tiny Δt "
                 "for the tension iteration to converge (transverse Courant number c_T·Δt/l, model.md 5.9)")


def _fmt(x: float) -> str:
    return f"{x:g}"


def _range_text(gt=None, ge=None, lt=None, le=None, unit="") -> str:
    lo = gt if gt is not None else ge
    hi = lt if lt is not None else le
    if lo is not None and hi is not None:
        s = f"in {'(' if gt is not None else '['}{_fmt(lo)}, {_fmt(hi)}{')' if lt is not None else ']'}"
    elif lo is not None:
        s = f"{'>' if gt is not None else '>='} {_fmt(lo)}"
    elif hi is not None:
        s = f"{'<' if lt is not None else '<='} {_fmt(hi)}"
    else:
        s = ""
    if unit:
        s = f"{s} {unit}" if s else f"({unit})"
    return s


def _is_number(v) -> bool:
    """A real number (int, float, numpy scalar), not a bool."""
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def _is_integer(v) -> bool:
    return isinstance(v, numbers.Integral) and not isinstance(v, bool)


def _to_float(v, what: str) -> float:
    if not _is_number(v):
        _value_error(f"must be a number{(' ' + what) if what else ''}")
    try:
        f = float(v)
    except (OverflowError, ValueError, TypeError):
        _value_error(f"must be a finite number{(' ' + what) if what else ''}")
    if not math.isfinite(f):
        _value_error(f"must be a finite number{(' ' + what) if what else ''}")
    return f


def _in_range(f, gt, ge, lt, le) -> bool:
    return not ((gt is not None and not f > gt) or (ge is not None and not f >= ge)
                or (lt is not None and not f < lt) or (le is not None and not f <= le))


def Num(*, gt=None, ge=None, lt=None, le=None, unit="", nonzero=False):
    """A finite float with optional bounds; the error message states the allowed range and unit."""
    rng = _range_text(gt, ge, lt, le, unit)

    def validate(v):
        f = _to_float(v, rng)
        if not _in_range(f, gt, ge, lt, le):
            _value_error(f"must be {rng}")
        if nonzero and f == 0.0:
            _value_error(f"must be non-zero{(' ' + unit) if unit else ''}")
        return f

    return Annotated[float, PlainValidator(validate)]


def Int(*, ge=None, le=None):
    """An integer (bools and floats are rejected) with optional bounds."""
    msg = f"must be an integer {_range_text(ge=ge, le=le)}".rstrip()

    def validate(v):
        if not _is_integer(v):
            _value_error(msg)
        i = int(v)
        if (ge is not None and i < ge) or (le is not None and i > le):
            _value_error(msg)
        return i

    return Annotated[int, PlainValidator(validate)]


def Vec3(*, gt=None, ge=None, lt=None, le=None, abs_le=None, unit="m"):
    """Three finite floats ``[x, y, z]`` (stored as a tuple)."""
    if abs_le is not None:
        rng = f"with |component| <= {_fmt(abs_le)}{(' ' + unit) if unit else ''}"
    else:
        r = _range_text(gt, ge, lt, le, "")
        rng = " ".join(x for x in ((f"each {r}" if r else ""), (f"({unit})" if unit else "")) if x)
    what = f"must be a list of 3 numbers [x, y, z]{(' ' + rng) if rng else ''}"

    def validate(v):
        if isinstance(v, (str, bytes, Mapping)) or not hasattr(v, "__len__") or not hasattr(v, "__iter__"):
            _value_error(what)
        try:
            items = list(v)
        except Exception:
            _value_error(what)
        if len(items) != 3 or not all(_is_number(x) for x in items):
            _value_error(what)
        out = []
        for x in items:
            try:
                f = float(x)
            except (OverflowError, ValueError, TypeError):
                _value_error(what)
            if not math.isfinite(f):
                _value_error(what)
            if abs_le is not None and abs(f) > abs_le:
                _value_error(what)
            if not _in_range(f, gt, ge, lt, le):
                _value_error(what)
            out.append(f)
        return tuple(out)

    return Annotated[tuple[float, float, float], PlainValidator(validate),
                     PlainSerializer(lambda v: [float(x) for x in v], return_type=list)]


def Matrix6(*, unit=""):
    """A 6×6 matrix of finite floats, six rows of six numbers (stored as a tuple of tuples)."""
    what = f"must be a 6x6 matrix: a list of 6 rows, each a list of 6 numbers{(' (' + unit + ')') if unit else ''}"

    def validate(v):
        if isinstance(v, (str, bytes, Mapping)) or not hasattr(v, "__iter__"):
            _value_error(what)
        rows = list(v)
        if len(rows) != 6:
            _value_error(what)
        out = []
        for i, row in enumerate(rows):
            if isinstance(row, (str, bytes, Mapping)) or not hasattr(row, "__iter__"):
                _value_error(what)
            items = list(row)
            if len(items) != 6 or not all(_is_number(x) for x in items):
                _value_error(f"{what}; row {i} is not 6 numbers")
            vals = []
            for j, x in enumerate(items):
                try:
                    f = float(x)
                except (OverflowError, ValueError, TypeError):
                    _value_error(what)
                if not math.isfinite(f):
                    _value_error(f"{what}; element [{i}][{j}] is not finite")
                vals.append(f)
            out.append(tuple(vals))
        return tuple(out)

    return Annotated[tuple[tuple[float, ...], ...], PlainValidator(validate),
                     PlainSerializer(lambda v: [[float(x) for x in r] for r in v], return_type=list)]


def _validate_name(v):
    if not isinstance(v, str) or not v.strip():
        _value_error("must be a non-empty string")
    bad = sorted({repr(c) for c in v if ord(c) < 32 or ord(c) == 127 or c == ","})
    if bad:
        # control characters (NUL, newline, tab …) and commas would break the CSV header, the Markdown
        # summary and file names; any other character round-trips through Result.save/load
        _value_error(f"must not contain control characters or commas (found {', '.join(bad)})")
    return v


def _validate_text(v):
    if not isinstance(v, str):
        _value_error("must be a string")
    return v


def _choice(*allowed: str):
    txt = " or ".join(f'"{a}"' for a in allowed)

    def validate(v):
        if not isinstance(v, str) or v not in allowed:
            _value_error(f"must be {txt}")
        return v

    return Annotated[str, PlainValidator(validate)]


def _validate_segments(v):
    msg = (f"must be an integer in [1, {MAX_SEGMENTS}] or a list of such integers, one per span (top end first), "
           f"{MAX_SEGMENTS} in all at most: {_SEGMENTS_WHY}")

    def one(x):
        if not _is_integer(x) or not 1 <= int(x) <= MAX_SEGMENTS:
            _value_error(msg)
        return int(x)

    if isinstance(v, (list, tuple)):
        if not v:
            _value_error(msg)
        out = tuple(one(x) for x in v)
        if sum(out) > MAX_SEGMENTS:
            _value_error(msg)
        return out
    return one(v)
