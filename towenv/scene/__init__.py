"""Scene description: validated, immutable data for a towed system (``docs/scene-format.md``).

A scene is a TOML file, a plain dict, or the name of a scene shipped in ``towenv/scenes/``::

    >>> from towenv.scene import load_scene, list_scenes
    >>> sc = load_scene("two_part_tow_1")            # embedded scene (the project default)
    >>> sc.line("primary").length
    85.0
    >>> sc.span_segments("primary")                  # segments per span, top end first
    [6, 2]
    >>> fast = sc.with_overrides({"vessel.speed": 4.0, "solver.dt": 0.01})

Every validation problem raises one :class:`SceneError` (a ``ValueError``) whose message lists each
offending field by its dotted path, what is allowed and the value given, e.g.
``lines[0].length: must be > 0 m (got -5.0)``. No pydantic or numpy exception escapes
:func:`load_scene`.

All models are frozen; derive variants with :meth:`Scene.with_overrides`.
"""
from .paths import DEFAULT_SCENE, SCENE_DATA_DIR, SCENES_DIR
from .errors import *  # noqa: F401,F403
from .errors import _INTERNAL, _allowed_fields, _convert_error, _problems, _short, _value_error  # noqa: F401
from .fields import *  # noqa: F401,F403
from .fields import MAX_SEGMENTS, Int, Num, Vec3, _choice  # noqa: F401
from .schema import *  # noqa: F401,F403
from .schema import _BodyBase, _Model, _TAG_CLASSES, distribute_segments  # noqa: F401
from .overrides import _set_path, _split_path  # noqa: F401
from .toml_writer import dumps_toml  # noqa: F401
from .loading import _embedded_names, _load_file, _validate, list_scenes, load_scene, scene_path  # noqa: F401

__all__ = [
    "scene_field",
    "SceneError", "Scene", "Water", "Current", "Vessel", "TurnManoeuvre", "SpeedChangeManoeuvre",
    "SinusoidExcitation", "TimeSeriesExcitation", "Ramp", "Line", "JunctionAttachment", "SpliceAttachment",
    "BodyAttachment",
    "PointBody", "RigidBody", "CoefficientTable", "Solver", "ManoeuvreWindow",
    "load_scene", "list_scenes", "scene_path", "DEFAULT_SCENE", "SCENES_DIR", "SCENE_DATA_DIR",
    "MAX_SEGMENTS",
]
