"""Errors and argument checks of the towenv environments (docs/environments.md "Errors and validation").

Three exception types, all documented:

* :class:`ConfigError` (a ``ValueError``) — an invalid constructor keyword or ``reset`` option. The message
  starts with the environment class and names the keyword / option, the allowed range or values and the
  value given.
* :class:`ActionError` (a ``ValueError``) — an action of the wrong shape or type. The message names the
  action space (shape, dtype, bounds) and what was given.
* :class:`ResetNeeded` (both ``gymnasium.error.ResetNeeded`` and ``RuntimeError``) — ``step`` before the first
  ``reset`` or after an episode ended (``terminated`` or ``truncated``).

Keyword arguments the constructor does not know raise Python's ``TypeError`` as usual.
"""
from __future__ import annotations

import math
import numbers
from typing import Any, Iterable, Mapping

import numpy as np
from gymnasium.error import ResetNeeded as _GymResetNeeded

__all__ = ["ConfigError", "ActionError", "ResetNeeded", "real", "integer", "choice", "real_seq", "mapping",
           "action_array"]


class ConfigError(ValueError):
    """Invalid environment constructor keyword or ``reset`` option (the message names it)."""


class ActionError(ValueError):
    """An action that does not fit the action space (wrong shape, or not real numbers)."""


class ResetNeeded(_GymResetNeeded, RuntimeError):
    """``step`` called before ``reset`` or after the episode ended (terminated or truncated)."""


def _is_real(v) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))


def _range_text(lo, hi, lo_open, hi_open) -> str:
    if lo is None and hi is None:
        return "a finite number"
    if hi is None:
        return f"a finite number {'>' if lo_open else '>='} {lo:g}"
    if lo is None:
        return f"a finite number {'<' if hi_open else '<='} {hi:g}"
    return f"a finite number in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"


def _unit(unit, lo, hi) -> str:
    return "" if not unit else f" ({unit})" if lo is None and hi is None else f" {unit}"


def real(owner: str, name: str, v: Any, lo: float | None = None, hi: float | None = None, *,
         lo_open: bool = False, hi_open: bool = False, none: str | None = None, unit: str = "") -> float | None:
    """``v`` as a float: a real number (not bool), finite and in the range. ``none``: if given, ``None`` is
    allowed and ``none`` says what it means (for the message)."""
    if v is None and none is not None:
        return None
    ok = _is_real(v)
    if ok:
        f = float(v)
        ok = (math.isfinite(f) and (lo is None or (f > lo if lo_open else f >= lo))
              and (hi is None or (f < hi if hi_open else f <= hi)))
    if not ok:
        what = _range_text(lo, hi, lo_open, hi_open) + _unit(unit, lo, hi)
        alt = f", or None ({none})" if none is not None else ""
        raise ConfigError(f"{owner}: {name} must be {what}{alt} (got {v!r})")
    return f


def integer(owner: str, name: str, v: Any, lo: int | None = None, hi: int | None = None, *,
            whole_floats: bool = False) -> int:
    """``v`` as an int: an integer (not bool; with ``whole_floats`` also a float with a whole value), in
    [lo, hi]."""
    ok = isinstance(v, numbers.Integral) and not isinstance(v, (bool, np.bool_))
    if not ok and whole_floats and _is_real(v):
        ok = math.isfinite(float(v)) and float(v).is_integer()
    if ok:
        i = int(v)
        ok = (lo is None or i >= lo) and (hi is None or i <= hi)
    if not ok:
        rng = ("" if lo is None and hi is None else f" >= {lo}" if hi is None else f" <= {hi}" if lo is None
               else f" in [{lo}, {hi}]")
        raise ConfigError(f"{owner}: {name} must be an integer{rng} (got {v!r})")
    return i


def choice(owner: str, name: str, v: Any, allowed: Iterable, *, none: str | None = None):
    """``v`` if it is one of ``allowed`` (or None when ``none`` says what None means)."""
    if v is None and none is not None:
        return None
    allowed = list(allowed)
    if not isinstance(v, str) or v not in allowed:
        alt = f" or None ({none})" if none is not None else ""
        raise ConfigError(f"{owner}: {name} must be one of {allowed}{alt} (got {v!r})")
    return v


def real_seq(owner: str, name: str, v: Any, lo: float | None = None, hi: float | None = None, *,
             lo_open: bool = False, empty: bool = True, none: str | None = None, unit: str = "") -> tuple | None:
    """A sequence (not a string or mapping) of real numbers, each finite and in the range."""
    if v is None and none is not None:
        return None
    alt = f", or None ({none})" if none is not None else ""
    what = f"a {'' if empty else 'non-empty '}sequence of numbers, each " + _range_text(lo, hi, lo_open, False) \
        + _unit(unit, lo, hi)
    if isinstance(v, (str, bytes, Mapping)) or not _iterable(v):
        raise ConfigError(f"{owner}: {name} must be {what}{alt} (got {v!r})")
    vals = list(v)
    if not empty and not vals:
        raise ConfigError(f"{owner}: {name} must be {what}{alt} (got {v!r})")
    out = []
    for x in vals:
        if not _is_real(x) or not math.isfinite(float(x)) or (lo is not None and (
                float(x) <= lo if lo_open else float(x) < lo)) or (hi is not None and float(x) > hi):
            raise ConfigError(f"{owner}: {name} must be {what}{alt} (got {v!r}; bad entry {x!r})")
        out.append(float(x))
    return tuple(out)


def mapping(owner: str, name: str, v: Any, *, none: str = "none") -> dict:
    """``v`` as a dict with string keys (``None`` -> ``{}``)."""
    if v is None:
        return {}
    if not isinstance(v, Mapping) or not all(isinstance(k, str) for k in v):
        raise ConfigError(f"{owner}: {name} must be a mapping with string keys, or None ({none}) (got {v!r})")
    return dict(v)


def _iterable(v) -> bool:
    try:
        iter(v)
    except TypeError:
        return False
    return True


def action_array(action: Any, shape: tuple, space_text, what: str = "action", also: tuple = ()) -> np.ndarray:
    """The slow path of the action check: ``action`` as a float64 array of ``shape`` — given in exactly that
    shape or one of the shapes ``also`` (e.g. ``()``, a scalar, for a one-dimensional action), made of real
    numbers (float or integer dtype; not bool, complex, strings or objects); otherwise :class:`ActionError`
    naming the action space (``space_text()``)."""
    try:
        a = np.asarray(action)
    except Exception as exc:                              # e.g. ragged nested lists
        raise ActionError(f"{what} {action!r} is not an array of real numbers ({exc}); "
                          f"the action space is {space_text()}") from None
    if a.dtype.kind not in "fiu":
        kind = {"b": "bool", "c": "complex", "U": "string", "S": "bytes", "O": "object"}.get(a.dtype.kind, str(a.dtype))
        raise ActionError(f"{what} must be real numbers (float or integer), got {kind} values {action!r}; "
                          f"the action space is {space_text()}")
    if a.shape != shape and a.shape not in also:
        alt = "".join(f" or {s}" for s in also)
        raise ActionError(f"{what} must have shape {shape}{alt}, got shape {a.shape}; "
                          f"the action space is {space_text()}")
    return np.array(a, dtype=float).reshape(shape)
