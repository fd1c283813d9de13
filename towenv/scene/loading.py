"""Loading scenes: a TOML file, a dict, an embedded scene's name or a Scene → a validated :class:`Scene`.
"""
import copy
import tomllib
from collections.abc import Mapping
from os import PathLike
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from .errors import SceneError, _INTERNAL, _short
from .paths import DEFAULT_SCENE, SCENES_DIR, SCENE_DATA_DIR
from .schema import Scene


def scene_path(name: str) -> Path:
    """Path of an embedded scene file."""
    return SCENES_DIR / f"{name}.toml"


def _embedded_names() -> list[str]:
    try:
        return sorted(p.stem for p in SCENES_DIR.glob("*.toml"))
    except OSError:  # pragma: no cover
        return []


def list_scenes() -> dict[str, str]:
    """Embedded scenes: ``{name: one-line description}`` (the first line of each ``description``)."""
    out = {}
    for name in _embedded_names():
        try:
            with open(scene_path(name), "rb") as fh:
                desc = tomllib.load(fh).get("description", "")
        except (OSError, tomllib.TOMLDecodeError):  # pragma: no cover
            desc = ""
        first = next((s.strip() for s in str(desc).splitlines() if s.strip()), "")
        out[name] = first
    return out


def _validate(data: Any, base_dir, source: str | None) -> Scene:
    if not isinstance(data, Mapping):
        raise SceneError([("", f"a scene must be a table/dict (got {_short(data)})")], source)
    try:
        sc = Scene.model_validate(dict(data), context={"base_dir": base_dir})
    except ValidationError as exc:
        raise SceneError.from_validation_error(exc, source) from None
    except SceneError:
        raise
    except RecursionError:
        raise SceneError([("", "scene data is nested too deeply")], source) from None
    except Exception as exc:   # never leak a raw traceback from validation
        raise SceneError([("", f"{_INTERNAL}: {type(exc).__name__}: {exc}")], source) from None
    sc._source_dir = str(base_dir) if base_dir is not None else None
    return sc


def _load_file(path: Path, base_dir=None) -> Scene:
    src = str(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise SceneError([("", f"scene file not found: {path}")]) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError([("", f"cannot read scene file {path}: {exc}")]) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError([("", f"invalid TOML: {exc}")], src) from None
    return _validate(data, base_dir if base_dir is not None else path.resolve().parent, src)


def load_scene(source: Any = None, *, base_dir=None) -> Scene:
    """Load and validate a scene.

    ``source``: a :class:`Scene` (returned as is), a dict, a path to a ``.toml`` file, or the name of an
    embedded scene (see :func:`list_scenes`); ``None`` loads :data:`DEFAULT_SCENE`. ``base_dir`` overrides
    the folder against which relative time-series paths resolve. Raises :class:`SceneError` on any
    problem."""
    if source is None:
        source = DEFAULT_SCENE
    if isinstance(source, Scene):
        return source
    if isinstance(source, Mapping):
        return _validate(copy.deepcopy(dict(source)), base_dir, None)
    if isinstance(source, (str, PathLike)):
        s = str(source) if isinstance(source, str) else None
        names = _embedded_names()
        if s is not None and s in names:
            return _load_file(scene_path(s), base_dir if base_dir is not None else SCENE_DATA_DIR)
        p = Path(source)
        if p.is_file() or p.suffix.lower() == ".toml":
            return _load_file(p, base_dir)
        raise SceneError([("", f"unknown scene {str(source)!r}: not a scene file and not an embedded scene "
                               f"(embedded: {', '.join(names) or 'none'})")])
    raise SceneError([("", f"cannot load a scene from a {type(source).__name__}; give a path, a dict, a Scene "
                           f"or an embedded scene name")])
