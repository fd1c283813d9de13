"""The scene schema (pydantic v2 models, all frozen): water, current, vessel and its manoeuvres/excitation,
lines, bodies, solver, sea, compensator, winch, and the :class:`Scene` that checks the topology. The one source
of every default the simulator uses (read through :func:`scene_field`).
"""
import copy
import csv
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any, Literal, NamedTuple, Union

from pydantic import BaseModel, ConfigDict, Discriminator, Field, PrivateAttr, Tag, ValidationInfo, model_validator
from pydantic.functional_serializers import PlainSerializer
from pydantic.functional_validators import PlainValidator

from .errors import SceneError, _problems, _short
from .fields import Int, MAX_SEGMENTS, Matrix6, Num, Vec3, _SEGMENTS_WHY, _choice, _validate_name, _validate_segments, _validate_text
from .overrides import _clean, _set_path
from .toml_writer import dumps_toml


def scene_field(obj, name: str, default=None):
    """``obj.name`` of a scene model (``obj[name]`` of a mapping; ``default`` for ``None``). The one accessor the
    core uses to read a validated scene: its defaults are the schema's, ``default`` only stands for a field
    a model *kind* does not have (e.g. a point body's ``dof``) — never a second copy of a schema default."""
    if obj is None:
        return default
    if isinstance(obj, Mapping):
        return obj.get(name, default)
    return getattr(obj, name, default)


Name = Annotated[str, PlainValidator(_validate_name)]


Text = Annotated[str, PlainValidator(_validate_text)]


Segments = Annotated[Union[int, tuple[int, ...]], PlainValidator(_validate_segments),
                     PlainSerializer(lambda v: list(v) if isinstance(v, tuple) else v, return_type=Any)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, validate_default=False)


class Water(_Model):
    """Water density and gravity."""
    density: Num(ge=500, le=2000, unit="kg/m^3") = 1025.0
    gravity: Num(gt=0, le=20, unit="m/s^2") = 9.80665


Depth = Num(ge=0, unit="m")


CurrentVec = Vec3(abs_le=10, unit="m/s")


class Current(_Model):
    """Uniform current ``velocity`` or a depth profile (``depths`` + ``velocities``); default none."""
    velocity: CurrentVec | None = None
    depths: tuple[Depth, ...] | None = None
    velocities: tuple[CurrentVec, ...] | None = None

    @model_validator(mode="after")
    def _check(self):
        probs = []
        has_profile = self.depths is not None or self.velocities is not None
        if self.velocity is not None and has_profile:
            probs.append(("velocity", "give either a uniform velocity or a depth profile "
                                      "(depths + velocities), not both"))
        if has_profile:
            if self.depths is None:
                probs.append(("depths", "required with velocities (depths in m, >= 0, strictly increasing)"))
            elif self.velocities is None:
                probs.append(("velocities", "required with depths (one [u, v, w] per depth)"))
            else:
                if len(self.depths) == 0:
                    probs.append(("depths", "must have at least 1 entry"))
                if len(self.depths) != len(self.velocities):
                    probs.append(("velocities", f"must have one [u, v, w] per depth: {len(self.depths)} depths "
                                                f"(got {len(self.velocities)} velocities)"))
                for i in range(1, len(self.depths)):
                    if not self.depths[i] > self.depths[i - 1]:
                        probs.append((f"depths[{i}]", f"must be strictly increasing: > {self.depths[i - 1]!r} m "
                                                      f"(got {self.depths[i]!r})"))
                        break
        if probs:
            _problems(*probs)
        return self

    @property
    def is_uniform(self) -> bool:
        return self.depths is None

    def velocity_at(self, z: float) -> tuple[float, float, float]:
        """Current at height ``z`` (depth ``-z``): linear in depth, held beyond the ends."""
        if self.depths is None:
            return self.velocity or (0.0, 0.0, 0.0)
        d = max(-float(z), 0.0)
        ds, vs = self.depths, self.velocities
        if d <= ds[0]:
            return vs[0]
        if d >= ds[-1]:
            return vs[-1]
        for i in range(1, len(ds)):
            if d <= ds[i]:
                w = (d - ds[i - 1]) / (ds[i] - ds[i - 1])
                return tuple(a + w * (b - a) for a, b in zip(vs[i - 1], vs[i]))
        return vs[-1]  # pragma: no cover


Speed = Num(ge=0, le=30, unit="m/s")


class TurnManoeuvre(_Model):
    """Constant-radius turn at constant speed; positive ``angle_deg`` turns to port."""
    type: Literal["turn"]
    start_time: Num(ge=0, unit="s")
    radius: Num(gt=0, unit="m")
    angle_deg: Num(unit="deg", nonzero=True)
    speed: Num(gt=0, le=30, unit="m/s") | None = None


class SpeedChangeManoeuvre(_Model):
    """Linear change of speed over ``duration``."""
    type: Literal["speed_change"]
    start_time: Num(ge=0, unit="s")
    duration: Num(gt=0, unit="s")
    final_speed: Speed


class SinusoidExcitation(_Model):
    """Tow-point displacement ``amplitude * sin(2 pi t / period + phase)`` along a global axis."""
    type: Literal["sinusoid"]
    axis: _choice("x", "y", "z")
    amplitude: Num(ge=0, unit="m")
    period: Num(gt=0, unit="s")
    phase_deg: Num(unit="deg") = 0.0


def _read_time_series(path: Path):
    """Read and check a ``t,x,y,z`` CSV; returns (t list, xyz list). Raises ValueError with a message."""
    if not path.is_file():
        raise ValueError(f"file not found: {path}")
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ValueError(f"cannot read {path}: {exc}") from None
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if not rows:
        raise ValueError(f"{path} is empty; expected a header t,x,y,z and at least 2 rows")
    header = [c.strip().lower() for c in rows[0]]
    if header != ["t", "x", "y", "z"]:
        raise ValueError(f"{path}: header must be t,x,y,z (got {','.join(rows[0])})")
    data = rows[1:]
    if len(data) < 2:
        raise ValueError(f"{path}: needs at least 2 data rows (got {len(data)})")
    ts, xyz = [], []
    for k, r in enumerate(data, start=2):
        if len(r) != 4:
            raise ValueError(f"{path} line {k}: expected 4 values t,x,y,z (got {len(r)})")
        try:
            vals = [float(c) for c in r]
        except ValueError:
            raise ValueError(f"{path} line {k}: values must be numbers (got {','.join(r)})") from None
        if not all(math.isfinite(x) for x in vals):
            raise ValueError(f"{path} line {k}: values must be finite (got {','.join(r)})")
        if ts and not vals[0] > ts[-1]:
            raise ValueError(f"{path} line {k}: t must be strictly increasing (got {vals[0]!r} after {ts[-1]!r})")
        ts.append(vals[0])
        xyz.append(tuple(vals[1:]))
    return ts, xyz


def _resolve(file: str, base_dir) -> Path:
    p = Path(file)
    if file.startswith("~"):
        try:
            p = p.expanduser()
        except RuntimeError:            # unknown user / no home directory: leave it as given
            pass
    if not p.is_absolute():
        p = Path(base_dir if base_dir is not None else Path.cwd()) / p
    return p


class TimeSeriesExcitation(_Model):
    """Tow-point offsets from a CSV ``t,x,y,z`` (linear interpolation, held at the last value).

    Relative ``file`` paths resolve against the scene file's folder (``SCENE_DATA_DIR`` for embedded
    scenes, the working directory for dicts unless ``load_scene(..., base_dir=...)`` is given)."""
    type: Literal["time_series"]
    file: Name

    @model_validator(mode="after")
    def _check_file(self, info: ValidationInfo):
        base = (info.context or {}).get("base_dir") if info is not None else None
        path = _resolve(self.file, base)
        try:
            _read_time_series(path)
        except ValueError as exc:
            _problems(("file", f"{exc} (got {self.file!r})"))
        return self

    def resolve(self, base_dir=None) -> Path:
        """Absolute path of the CSV (relative paths against ``base_dir``, default the working dir)."""
        return _resolve(self.file, base_dir)

    def load(self, base_dir=None):
        """``(t, xyz)`` as lists (times in s, offsets in m)."""
        return _read_time_series(self.resolve(base_dir))


class Ramp(_Model):
    """Start-up ramp of the oscillatory excitation only."""
    type: _choice("half_cosine", "exponential", "none") = "half_cosine"
    duration: Num(ge=0, unit="s") = 12.0

    def __call__(self, t: float) -> float:
        if self.type == "none" or self.duration <= 0:
            return 1.0
        if self.type == "exponential":
            return 1.0 - math.exp(-max(t, 0.0) / self.duration)
        x = min(max(t / self.duration, 0.0), 1.0)
        return 0.5 * (1.0 - math.cos(math.pi * x))


def _tag_by_key(key: str, mapping: dict[str, str], classes: tuple[type, ...]):
    def disc(v):
        if isinstance(v, Mapping):
            val = v.get(key)
            return mapping.get(val) if isinstance(val, str) else None
        for cls in classes:
            if isinstance(v, cls):
                return mapping.get(getattr(v, key, None))
        return None
    return disc


Manoeuvre = Annotated[
    Union[Annotated[TurnManoeuvre, Tag("@turn")], Annotated[SpeedChangeManoeuvre, Tag("@speed_change")]],
    Discriminator(_tag_by_key("type", {"turn": "@turn", "speed_change": "@speed_change"},
                              (TurnManoeuvre, SpeedChangeManoeuvre)),
                  custom_error_type="bad_manoeuvre", custom_error_message="invalid manoeuvre type"),
]


Excitation = Annotated[
    Union[Annotated[SinusoidExcitation, Tag("@sinusoid")], Annotated[TimeSeriesExcitation, Tag("@time_series")]],
    Discriminator(_tag_by_key("type", {"sinusoid": "@sinusoid", "time_series": "@time_series"},
                              (SinusoidExcitation, TimeSeriesExcitation)),
                  custom_error_type="bad_excitation", custom_error_message="invalid excitation type"),
]


class ManoeuvreWindow(NamedTuple):
    """One manoeuvre in time: ``[start_time, end_time]`` and the speed at both ends."""
    index: int
    type: str
    start_time: float
    end_time: float
    initial_speed: float
    final_speed: float


class Vessel(_Model):
    """Tow-point motion: steady tow, manoeuvres (in the order given), oscillatory excitation and the
    wave-induced motion of the vessel (``model`` preset or ``rao_file`` with a ``[sea]``, or a measured
    ``motion_file``), transferred to the tow point through ``lever_arm`` (tow point relative to the
    vessel's centre of gravity, ship axes x forward, y port, z up; default: the preset's tow point)."""
    tow_point: Vec3(unit="m") = (0.0, 0.0, 0.0)
    speed: Speed = 0.0
    heading_deg: Num(unit="deg") = 0.0
    manoeuvres: tuple[Manoeuvre, ...] = ()
    excitation: tuple[Excitation, ...] = ()
    ramp: Ramp = Ramp()
    model: _choice("coastal_survey", "research_vessel") | None = None
    rao_file: Text | None = None
    motion_file: Text | None = None
    lever_arm: Vec3(unit="m") | None = None

    @model_validator(mode="after")
    def _check_motion_source(self):
        given = [n for n in ("model", "rao_file", "motion_file") if getattr(self, n) is not None]
        if "rao_file" in given and "motion_file" in given:
            _problems(("motion_file", "give either rao_file (with [sea]) or motion_file (a measured record), "
                                      "not both"))
        return self

    def schedule(self) -> list[ManoeuvreWindow]:
        """Start/end times and speeds of the manoeuvres (a turn at zero speed never ends: ``inf``)."""
        out, v = [], self.speed
        for i, m in enumerate(self.manoeuvres):
            if isinstance(m, TurnManoeuvre):
                vt = v if m.speed is None else m.speed
                dur = math.inf if vt <= 0 else m.radius * math.radians(abs(m.angle_deg)) / vt
                out.append(ManoeuvreWindow(i, "turn", m.start_time, m.start_time + dur, vt, vt))
                v = vt
            else:
                out.append(ManoeuvreWindow(i, "speed_change", m.start_time, m.start_time + m.duration,
                                           v, m.final_speed))
                v = m.final_speed
        return out

    @model_validator(mode="after")
    def _check_schedule(self):
        probs = []
        v = self.speed
        prev_end, prev_i = 0.0, None
        for i, m in enumerate(self.manoeuvres):
            if prev_i is not None and m.start_time < prev_end - 1e-9:
                probs.append((f"manoeuvres[{i}].start_time",
                              f"must be >= {prev_end:.6g} s, the end of manoeuvres[{prev_i}] (manoeuvres run in "
                              f"the order given and must not overlap) (got {m.start_time!r})"))
            if isinstance(m, TurnManoeuvre):
                if m.speed is not None and not math.isclose(m.speed, v, rel_tol=1e-9, abs_tol=1e-9):
                    probs.append((f"manoeuvres[{i}].speed",
                                  f"must equal the vessel speed at start_time ({v:g} m/s); change speed with a "
                                  f"speed_change manoeuvre (got {m.speed!r})"))
                vt = v if m.speed is None else m.speed
                if vt <= 0:
                    probs.append((f"manoeuvres[{i}]", "a turn needs a positive speed: the vessel speed at "
                                                      "start_time is 0 m/s (set vessel.speed or add a speed_change)"))
                    dur = math.inf
                else:
                    dur = m.radius * math.radians(abs(m.angle_deg)) / vt
                v = vt
            else:
                dur = m.duration
                v = m.final_speed
            prev_end, prev_i = m.start_time + dur, i
        if probs:
            _problems(*probs)
        return self


class JunctionAttachment(_Model):
    """Top of a line on another line: ``distance`` (m) along that line's unstretched length from its top."""
    line: Name
    distance: Num(gt=0, unit="m")


class SpliceAttachment(_Model):
    """Top of a line spliced to the bottom end of another line (which must end ``"free"``): the two lines share
    that node, each with its own properties on its side — one cable of piecewise properties."""
    splice: Name


class BodyAttachment(_Model):
    """A body: as a line ``bottom`` its tow point; as a line ``top`` its ``aft_tow_point``."""
    body: Name


class AnchorAttachment(_Model):
    """A fixed point in space (global coordinates, m): moorings and verification cases."""
    anchor: Vec3(abs_le=1e6, unit="m")


def _top_disc(v):
    if isinstance(v, str):
        return "@vessel" if v == "vessel" else None
    if isinstance(v, JunctionAttachment):
        return "@junction"
    if isinstance(v, SpliceAttachment):
        return "@splice"
    if isinstance(v, BodyAttachment):
        return "@body_top"
    if isinstance(v, Mapping):
        if "line" in v:
            return "@junction"
        if "splice" in v:
            return "@splice"
        if "body" in v:
            return "@body_top"
    return None


def _bottom_disc(v):
    if isinstance(v, str):
        return "@free" if v == "free" else None
    if isinstance(v, BodyAttachment) or (isinstance(v, Mapping) and "body" in v):
        return "@body_bottom"
    if isinstance(v, AnchorAttachment) or (isinstance(v, Mapping) and "anchor" in v):
        return "@anchor"
    return None


Top = Annotated[
    Union[Annotated[Literal["vessel"], Tag("@vessel")], Annotated[JunctionAttachment, Tag("@junction")],
          Annotated[SpliceAttachment, Tag("@splice")], Annotated[BodyAttachment, Tag("@body_top")]],
    Discriminator(_top_disc, custom_error_type="bad_top", custom_error_message="invalid top attachment"),
]


Bottom = Annotated[
    Union[Annotated[Literal["free"], Tag("@free")], Annotated[BodyAttachment, Tag("@body_bottom")],
          Annotated[AnchorAttachment, Tag("@anchor")]],
    Discriminator(_bottom_disc, custom_error_type="bad_bottom", custom_error_message="invalid bottom attachment"),
]


BULK_DENSITY_RANGE = (300.0, 20000.0)


def distribute_segments(total: int, spans: list[float]) -> list[int]:
    """Split ``total`` segments over ``spans`` (lengths) in proportion to length, at least 1 per span.

    Rounds ``total * span / sum``, then fixes the sum by moving single segments: removing from the span
    with the shortest segments (among spans with more than one) or adding to the span with the longest.
    If ``total`` is smaller than the number of spans every span gets 1 (the total is then exceeded)."""
    k = len(spans)
    if k == 0:
        return []
    tot_len = float(sum(spans))
    counts = [max(1, int(round(total * s / tot_len))) if tot_len > 0 else 1 for s in spans]
    while sum(counts) > max(total, k):
        cand = [i for i in range(k) if counts[i] > 1]
        i = max(cand, key=lambda j: (counts[j] / spans[j] if spans[j] > 0 else math.inf, -j))
        counts[i] -= 1
    while sum(counts) < total:
        i = max(range(k), key=lambda j: (spans[j] / counts[j], -j))
        counts[i] += 1
    return counts


class Line(_Model):
    """A cable. ``segments`` is an int (spread over the spans) or one int per span, top end first."""
    name: Name
    length: Num(gt=0, unit="m")
    segments: Segments
    diameter: Num(ge=1e-4, le=1, unit="m")          # 0.1 mm: thinner is not a cable (and its area underflows)
    mass_per_length: Num(gt=0, unit="kg/m")
    EA: Num(gt=0, unit="N")
    cn: Num(ge=0) = 1.2
    ct: Num(ge=0) = 0.01
    can: Num(ge=0) = 1.0
    cat: Num(ge=0) = 0.0
    top: Top
    bottom: Bottom

    @model_validator(mode="after")
    def _check_density(self):
        rho_c = self.bulk_density
        lo, hi = BULK_DENSITY_RANGE
        if not lo <= rho_c <= hi:
            _problems(("mass_per_length",
                       f"implies a cable bulk density mass_per_length/(pi*diameter^2/4) = {rho_c:.4g} kg/m^3, "
                       f"outside {lo:g}-{hi:g} kg/m^3; check units (diameter in m, mass_per_length in kg/m) "
                       f"(got mass_per_length={self.mass_per_length!r}, diameter={self.diameter!r})"))
        return self

    @property
    def bulk_density(self) -> float:
        return self.mass_per_length / (math.pi * self.diameter ** 2 / 4.0)

    @property
    def top_kind(self) -> str:
        """``"vessel"``, ``"line"`` (junction), ``"splice"`` (the bottom end of another line) or ``"body"`` (a body's
        aft tow point)."""
        if isinstance(self.top, JunctionAttachment):
            return "line"
        if isinstance(self.top, SpliceAttachment):
            return "splice"
        if isinstance(self.top, BodyAttachment):
            return "body"
        return "vessel"

    @property
    def bottom_body(self) -> str | None:
        return self.bottom.body if isinstance(self.bottom, BodyAttachment) else None

    def wet_weight_per_length(self, water: "Water | None" = None) -> float:
        """Weight in water per unit length (N/m); negative for a buoyant cable."""
        w = water or Water()
        return (self.mass_per_length - w.density * math.pi * self.diameter ** 2 / 4.0) * w.gravity

    def span_bounds(self, junction_distances=()) -> list[float]:
        """``[0, d1, d2, ..., length]``: the attachment points along the line (unique, sorted)."""
        cuts = sorted({float(d) for d in junction_distances if 0.0 < float(d) < self.length})
        return [0.0] + cuts + [self.length]

    def span_segments(self, junction_distances=()) -> list[int]:
        """Segments per span, top end first, for junctions at ``junction_distances`` (m from the top).

        A list ``segments`` is returned as given (its length must equal the number of spans); an int is
        distributed in proportion to span length with at least 1 per span (:func:`distribute_segments`)."""
        b = self.span_bounds(junction_distances)
        spans = [b[i + 1] - b[i] for i in range(len(b) - 1)]
        if isinstance(self.segments, tuple):
            if len(self.segments) != len(spans):
                raise ValueError(f"line {self.name!r}: segments lists {len(self.segments)} counts but the line "
                                 f"has {len(spans)} spans")
            return list(self.segments)
        return distribute_segments(self.segments, spans)


class CoefficientTable(_Model):
    """Force/moment coefficients vs incidence. A table starting at 0 deg is mirrored (drag even, lift and
    moment odd); outside the table the end value is held."""
    incidence_deg: tuple[Num(ge=-180, le=180, unit="deg"), ...]
    drag: tuple[Num(ge=0), ...]
    lift: tuple[Num(), ...]
    moment: tuple[Num(), ...]

    @model_validator(mode="after")
    def _check(self):
        probs = []
        n = len(self.incidence_deg)
        if n < 2:
            probs.append(("incidence_deg", f"must have at least 2 entries (got {n})"))
        for i in range(1, n):
            if not self.incidence_deg[i] > self.incidence_deg[i - 1]:
                probs.append((f"incidence_deg[{i}]", f"must be strictly increasing: > {self.incidence_deg[i - 1]!r} "
                                                     f"deg (got {self.incidence_deg[i]!r})"))
                break
        for col in ("drag", "lift", "moment"):
            m = len(getattr(self, col))
            if m != n:
                probs.append((col, f"must have the same length as incidence_deg ({n}) (got {m})"))
        if probs:
            _problems(*probs)
        return self

    @property
    def mirrored(self) -> bool:
        return self.incidence_deg[0] == 0.0

    def full(self) -> tuple[list[float], list[float], list[float], list[float]]:
        """Columns over the full range: a table starting at 0 is mirrored (drag even; lift and moment odd
        about their value at 0, i.e. ``f(-a) = 2 f(0) - f(a)``, which is plain odd when ``f(0) = 0``)."""
        inc, cd, cl, cm = map(list, (self.incidence_deg, self.drag, self.lift, self.moment))
        if not self.mirrored:
            return inc, cd, cl, cm
        return ([-a for a in inc[:0:-1]] + inc, cd[:0:-1] + cd,
                [2 * cl[0] - c for c in cl[:0:-1]] + cl, [2 * cm[0] - c for c in cm[:0:-1]] + cm)

    def evaluate(self, incidence_deg: float) -> tuple[float, float, float]:
        """``(drag, lift, moment)`` at an incidence (deg), linear interpolation, end values held."""
        inc, cd, cl, cm = self.full()
        a = float(incidence_deg)
        if a <= inc[0]:
            return cd[0], cl[0], cm[0]
        if a >= inc[-1]:
            return cd[-1], cl[-1], cm[-1]
        for i in range(1, len(inc)):
            if a <= inc[i]:
                w = (a - inc[i - 1]) / (inc[i] - inc[i - 1])
                return tuple(c[i - 1] + w * (c[i] - c[i - 1]) for c in (cd, cl, cm))
        return cd[-1], cl[-1], cm[-1]  # pragma: no cover

    def without_lift_offset(self) -> "CoefficientTable":
        """The same table with the lift at zero incidence subtracted (depressor horizontal default)."""
        l0 = self.evaluate(0.0)[1]
        if l0 == 0.0:
            return self
        return self.model_copy(update={"lift": tuple(c - l0 for c in self.lift)})


class _BodyBase(_Model):
    name: Name
    mass: Num(gt=0, unit="kg")
    volume: Num(ge=0, unit="m^3")

    @property
    def is_rigid(self) -> bool:
        return self.kind in ("fish", "depressor")

    def wet_weight(self, water: "Water | None" = None) -> float:
        """Weight in water (N); negative if buoyant."""
        w = water or Water()
        return (self.mass - w.density * self.volume) * w.gravity


class PointBody(_BodyBase):
    """Translation-only body (ball, clump) with isotropic quadratic drag."""
    kind: Literal["ball", "clump"]
    drag_area: Num(ge=0, unit="m^2") = 0.0
    added_mass_coefficient: Num(ge=0) = 0.5


class RigidBody(_BodyBase):
    """6-DOF body (fish, depressor) about its tow point; offsets are body-axis vectors from the tow point."""
    kind: Literal["fish", "depressor"]
    inertia: Vec3(gt=0, unit="kg m^2")
    cg: Vec3(unit="m")
    cb: Vec3(unit="m") | None = None
    aft_tow_point: Vec3(unit="m") | None = None
    added_mass: Vec3(ge=0, unit="kg") = (0.0, 0.0, 0.0)
    added_inertia: Vec3(ge=0, unit="kg m^2") = (0.0, 0.0, 0.0)
    # the full (symmetric, positive semi-definite) 6x6 added mass over (surge, sway, heave, roll, pitch, yaw)
    # about the point ``added_mass_reference`` (body axes, from the tow point): instead of the diagonal above
    added_mass_matrix: Matrix6(unit="kg, kg m, kg m^2") | None = None
    added_mass_reference: Vec3(unit="m") = (0.0, 0.0, 0.0)
    # the added mass's Coriolis/centripetal terms (Kirchhoff; they include the Munk moment): off by default
    # because measured moment tables already contain the Munk moment (docs/scene-format.md)
    added_mass_coriolis: bool = False
    # a constant force in global axes at the centre of gravity: thrusters holding the body's station
    external_force: Vec3(abs_le=1e7, unit="N") = (0.0, 0.0, 0.0)
    reference_area: Num(gt=0, unit="m^2")
    reference_length: Num(gt=0, unit="m")
    coefficients: CoefficientTable
    horizontal_coefficients: CoefficientTable | None = None
    rotational_damping: Vec3(ge=0, unit="") = (0.1, 0.1, 0.1)
    quadratic_rotational_damping: Vec3(ge=0, unit="") = (0.5, 0.5, 0.5)
    dof: _choice("6dof", "surge_heave_pitch") = "6dof"      # surge_heave_pitch: roll and yaw held

    @model_validator(mode="after")
    def _check_added_mass(self):
        probs = []
        M = self.added_mass_matrix
        if M is None:
            if any(x != 0.0 for x in self.added_mass_reference):
                probs.append(("added_mass_reference", "is the point about which added_mass_matrix is given: set "
                                                      "added_mass_matrix too, or leave it out"))
        else:
            if any(x != 0.0 for x in self.added_mass) or any(x != 0.0 for x in self.added_inertia):
                probs.append(("added_mass_matrix", "give either added_mass/added_inertia (diagonal, at the tow "
                                                   "point) or added_mass_matrix, not both"))
            scale = max(abs(x) for r in M for x in r) or 1.0
            asym = [(i, j) for i in range(6) for j in range(i + 1, 6) if abs(M[i][j] - M[j][i]) > 1e-9 * scale]
            if asym:
                i, j = asym[0]
                probs.append((f"added_mass_matrix[{i}][{j}]", f"must equal added_mass_matrix[{j}][{i}]: an added-mass "
                                                             f"matrix is symmetric (got {M[i][j]!r} and {M[j][i]!r})"))
            else:
                import numpy as np
                lo = float(np.linalg.eigvalsh(np.array(M, float)).min())
                if lo < -1e-9 * scale:
                    probs.append(("added_mass_matrix", f"must be positive semi-definite (kinetic energy >= 0); its "
                                                       f"smallest eigenvalue is {lo:.6g}"))
        if probs:
            _problems(*probs)
        return self

    @property
    def centre_of_buoyancy(self) -> tuple[float, float, float]:
        """``cb``, defaulting to ``cg``."""
        return self.cb if self.cb is not None else self.cg

    @property
    def horizontal_table(self) -> CoefficientTable:
        """The effective horizontal-plane table: as given, else the vertical table (fish) or the vertical
        table with its zero-incidence lift removed (depressor)."""
        if self.horizontal_coefficients is not None:
            return self.horizontal_coefficients
        if self.kind == "depressor":
            return self.coefficients.without_lift_offset()
        return self.coefficients


Body = Annotated[
    Union[Annotated[RigidBody, Tag("@rigid")], Annotated[PointBody, Tag("@point")]],
    Discriminator(_tag_by_key("kind", {"fish": "@rigid", "depressor": "@rigid", "ball": "@point",
                                       "clump": "@point"}, (RigidBody, PointBody)),
                  custom_error_type="bad_body", custom_error_message="invalid body kind"),
]


_TAG_CLASSES = {
    "@turn": TurnManoeuvre, "@speed_change": SpeedChangeManoeuvre, "@sinusoid": SinusoidExcitation,
    "@time_series": TimeSeriesExcitation, "@junction": JunctionAttachment, "@splice": SpliceAttachment,
    "@body_top": BodyAttachment,
    "@body_bottom": BodyAttachment, "@rigid": RigidBody, "@point": PointBody, "@vessel": None, "@free": None,
}


class Solver(_Model):
    """Time integration (``method``: ``houbolt`` — implicit, Newton on the tensions, the default;
    ``generalized_alpha`` (high-frequency spectral radius ``rho_inf``) / ``newmark`` (average
    acceleration) — implicit, Newton on the positions of the elastic model; ``euler`` / ``rk2`` / ``rk4``
    — explicit, needs Δt below the axial CFL limit (``axial_damping_ratio`` ζ: c = 2ζ l √(EA μ), i.e.
    MoorDyn's BA = −2ζ; also used by the two implicit elastic schemes); ``quasi_static`` —
    static equilibrium at every step), time step and Newton-iteration settings."""
    method: _choice("houbolt", "generalized_alpha", "newmark", "euler", "rk2", "rk4", "quasi_static") = "houbolt"
    tension_solve: _choice("tree", "as_published") = "tree"
    axial_damping_ratio: Num(ge=0, le=10) = 0.0
    rho_inf: Num(ge=0, le=1) = 0.2
    # towenv.fidelity: choose dt, segments and 2-D/3-D for this relative tolerance of the fish statistics
    # (also used, at 0.05, for dt alone when the scene does not set dt; docs/fidelity.md)
    fidelity: Num(gt=0, lt=1) | None = None
    dt: Num(ge=1e-5, le=1, unit="s") = 0.02
    tolerance: Num(gt=0, unit="N") = 0.5
    relative_tolerance: Num(ge=0, lt=1) = 1e-5
    angle_tolerance: Num(gt=0, unit="rad") = 1e-5
    max_iterations: Int(ge=1) = 25
    max_step_cuts: Int(ge=0) = 4
    max_strain: Num(gt=0, le=1) = 0.2          # a cable stretched beyond twice its length has failed
    settle_time: Num(ge=0, le=3600, unit="s") = 0.0
    planar: bool = False        # 2-D vertical-plane model: lateral node motion, body roll and yaw frozen
    newton_stop: _choice("change", "estimate") = "change"
    # Houbolt's Newton predictor: each step chooses, per kind of unknown, the extrapolation (quadratic or cubic
    # positions and angles, linear or quadratic tensions) that would have predicted the last step better
    # ("adaptive"), or always the lower orders ("quadratic", the predictor before 2026-12-06; docs/architecture.md)
    predictor: _choice("adaptive", "quadratic") = "adaptive"
    # Houbolt's rigid-body load derivatives (rotational stiffness/damping, translational damping: rate-only
    # linearisations of the Newton iteration, found by finite differences): computed afresh every this many
    # steps and reused in between (1: every step, the kernel before this setting; docs/architecture.md)
    body_derivative_refresh: Int(ge=1, le=1000) = 10
    # Houbolt's free-node Newton matrices M̃ = M + (11Δt/12) B + ½Δt² K_g (drag Jacobians, string stiffness) and their
    # inverses: built afresh every this many steps and reused in between, a modified Newton (1: every iteration, the
    # kernel before this setting; not with a series tow's aft tow point; a step that needs
    # more iterations than the building step drops them; docs/architecture.md)
    cable_jacobian_refresh: Int(ge=1, le=1000) = 10
    # series tows: the tail's top segments in the body's clique of the tension solve ("monolithic"), or its pull
    # as a relaxed load inside the Newton loop ("relaxed", the coupling before 2026-12; docs/model-notes.md)
    series_coupling: _choice("monolithic", "relaxed") = "monolithic"


class Sea(_Model):
    """Irregular sea driving the vessel motion: ``hs``/``tp`` or a WMO sea-state ``code`` (0–9) with the
    ``open_ocean`` or ``coastal`` (fetch-limited) period convention; JONSWAP/Bretschneider/PM spectrum;
    ``heading_deg`` is the direction the waves travel relative to the ship's initial heading (180 = head
    seas); ``spreading_s`` makes the sea short-crested (cos-2s); the record is seeded.
    ``orbital_velocities`` lets the waves' (deep-water, exp(kz)-decaying) orbital velocities act on the
    cables' and bodies' drag (their inertia/Froude–Krylov loads are not modelled)."""
    hs: Num(ge=0, le=30, unit="m") | None = None
    tp: Num(gt=0, le=40, unit="s") | None = None
    code: Int(ge=0, le=9) | None = None
    convention: _choice("open_ocean", "coastal") = "open_ocean"
    spectrum: _choice("jonswap", "bretschneider", "pm") = "jonswap"
    gamma: Num(ge=1, le=10) | None = None
    heading_deg: Num(ge=-360, le=360, unit="deg") = 180.0
    spreading_s: Num(gt=0, le=100) | None = None
    seed: Int(ge=0) = 0
    n_components: Int(ge=10, le=5000) = 200
    orbital_velocities: bool = False

    @model_validator(mode="after")
    def _check(self):
        if self.code is None and (self.hs is None or self.tp is None):
            _problems(("hs", "give hs and tp (m, s), or a sea-state code (0-9)"))
        if self.code is not None and (self.hs is not None or self.tp is not None):
            _problems(("code", "give either a sea-state code or hs/tp, not both"))
        return self

    def sea_state(self):
        from ..sea import SeaState
        kw = dict(spectrum=self.spectrum, gamma=self.gamma, heading_deg=self.heading_deg,
                  spreading_s=self.spreading_s)
        if self.code is not None:
            return SeaState.from_code(self.code, convention=self.convention, **kw)
        return SeaState(self.hs, self.tp, **kw)


class Compensator(_Model):
    """Heave compensator between the vessel sheave and the cable top (Hover et al. §IV-A): spring k,
    damper b, apparent mass m moving with the top node, stroke ±stroke/2 about mid-stroke with rigid end
    stops (exact contact: the sheave is held at a stop while the stop pushes; hits are counted). ``mode``:
    ``passive`` (k, b changeable at run time within the bounds: semi-active), ``locked``, ``position``
    (commanded sheave position, first-order lag + rate limit) or ``force`` (commanded force, same)."""
    mode: _choice("passive", "locked", "position", "force") = "passive"
    stiffness: Num(ge=0, unit="N/m") = 0.0
    damping: Num(ge=0, unit="N s/m") = 0.0
    mass: Num(ge=0, unit="kg") = 0.0
    stroke: Num(gt=0, unit="m") = 2.0
    stiffness_bounds: tuple[Num(ge=0, unit="N/m"), Num(ge=0, unit="N/m")] = (0.0, 1.0e6)
    damping_bounds: tuple[Num(ge=0, unit="N s/m"), Num(ge=0, unit="N s/m")] = (0.0, 1.0e6)
    actuator_time_constant: Num(gt=0, unit="s") = 0.2
    rate_limit: Num(gt=0) = 1.0                     # m/s in position mode, N/s in force mode

    @model_validator(mode="after")
    def _check(self):
        probs = []
        for name in ("stiffness", "damping"):
            lo, hi = getattr(self, f"{name}_bounds")
            if lo > hi:
                probs.append((f"{name}_bounds", f"lower bound must be <= upper bound (got [{lo}, {hi}])"))
            elif not lo <= getattr(self, name) <= hi:
                probs.append((name, f"must lie within {name}_bounds [{lo:g}, {hi:g}] (got {getattr(self, name)!r})"))
        if probs:
            _problems(*probs)
        return self


class Winch(_Model):
    """Winch at the top of ``line`` (default: the line attached to the vessel). Payout is positive.
    ``mode``: ``speed`` (payout speed command, m/s) or ``constant_tension`` (pay out above
    ``set_tension``, haul in below, speed = gain × (T − set_tension) outside a deadband)."""
    line: Name | None = None
    mode: _choice("speed", "constant_tension") = "speed"
    speed: Num(unit="m/s") = 0.0
    max_speed: Num(gt=0, unit="m/s") = 1.0
    max_acceleration: Num(gt=0, unit="m/s^2") = 0.5
    min_length: Num(gt=0, unit="m") | None = None
    max_length: Num(gt=0, unit="m") | None = None
    nominal_segment_length: Num(gt=0, unit="m") | None = None
    set_tension: Num(ge=0, unit="N") = 0.0
    gain: Num(ge=0, unit="m/s/N") = 1.0e-4
    deadband: Num(ge=0, unit="N") = 0.0

    @model_validator(mode="after")
    def _check(self):
        if self.min_length is not None and self.max_length is not None and self.min_length > self.max_length:
            _problems(("min_length", f"must be <= max_length ({self.max_length:g} m) (got {self.min_length!r})"))
        if abs(self.speed) > self.max_speed:
            _problems(("speed", f"must be within ±max_speed = ±{self.max_speed:g} m/s (got {self.speed!r})"))
        return self


class Scene(_Model):
    """A validated towed-system scene. Build with :func:`load_scene`."""
    name: Name
    description: Text = ""
    water: Water = Water()
    current: Current = Current()
    vessel: Vessel = Vessel()
    lines: tuple[Line, ...] = Field(min_length=1)
    bodies: tuple[Body, ...] = ()
    sea: Sea | None = None
    compensator: Compensator | None = None
    winch: Winch | None = None
    solver: Solver = Solver()

    _source_dir: str | None = PrivateAttr(default=None)

    def __eq__(self, other: object) -> bool:
        """Equal content (the folder a scene was loaded from does not matter)."""
        if not isinstance(other, Scene):
            return NotImplemented
        return self.__dict__ == other.__dict__

    def __hash__(self) -> int:
        return hash((self.name, len(self.lines), len(self.bodies)))

    # ---------------------------------------------------------------- cross-field / topology checks
    @model_validator(mode="after")
    def _check_vessel_files(self, info):
        base = (info.context or {}).get("base_dir") if info is not None else None
        probs = []
        for fld in ("rao_file", "motion_file"):
            f = getattr(self.vessel, fld)
            if f is not None and not _resolve(f, base).exists():
                probs.append((f"vessel.{fld}", f"file not found: {f!r}"))
        if probs:
            _problems(*probs)
        return self

    @model_validator(mode="after")
    def _check_topology(self):
        probs: list[tuple[str, str]] = []
        lines, bodies = self.lines, self.bodies
        line_idx: dict[str, int] = {}
        for i, ln in enumerate(lines):
            if ln.name in line_idx:
                probs.append((f"lines[{i}].name", f"duplicate line name {ln.name!r} (also lines[{line_idx[ln.name]}])"))
            else:
                line_idx[ln.name] = i
        body_idx: dict[str, int] = {}
        for k, b in enumerate(bodies):
            if b.name in body_idx:
                probs.append((f"bodies[{k}].name", f"duplicate body name {b.name!r} (also bodies[{body_idx[b.name]}])"))
            else:
                body_idx[b.name] = k
        known_lines = ", ".join(repr(n) for n in line_idx) or "none"
        known_bodies = ", ".join(repr(n) for n in body_idx) or "none"

        refs_ok = True
        roots: list[int] = []
        bottom_of: dict[str, list[int]] = {}
        spliced_to: dict[str, str] = {}
        def parent_line(i, ln, field, ref, verb):
            """The line ``ref`` names in lines[i].top.<field>, or None after recording why it cannot be."""
            if ref not in line_idx:
                probs.append((f"lines[{i}].top.{field}", f"unknown line {ref!r} (known lines: {known_lines})"))
                return None
            if ref == ln.name:
                probs.append((f"lines[{i}].top.{field}", f"a line cannot {verb} itself (got {ref!r})"))
                return None
            return lines[line_idx[ref]]

        for i, ln in enumerate(lines):
            top = ln.top
            if isinstance(top, JunctionAttachment):
                parent = parent_line(i, ln, "line", top.line, "hang from")
                refs_ok = refs_ok and parent is not None
                if parent is not None and not top.distance < parent.length:
                    probs.append((f"lines[{i}].top.distance",
                                  f"must be < {parent.length:g} m, the length of line {top.line!r} "
                                  f"(junction beyond the line's end) (got {top.distance!r})"))
            elif isinstance(top, SpliceAttachment):
                parent = parent_line(i, ln, "splice", top.splice, "be spliced to")
                refs_ok = refs_ok and parent is not None
                if parent is None:
                    pass
                elif parent.bottom != "free":
                    refs_ok = False
                    probs.append((f"lines[{i}].top.splice",
                                  f"line {top.splice!r} must end free (bottom = \"free\") to be continued by a "
                                  f"splice; its bottom is {parent.bottom!r}"))
                elif top.splice in spliced_to:
                    refs_ok = False
                    probs.append((f"lines[{i}].top.splice",
                                  f"line {top.splice!r} is already continued by line {spliced_to[top.splice]!r} "
                                  f"(one line per splice; hang more lines from a junction)"))
                else:
                    spliced_to[top.splice] = ln.name
            elif isinstance(top, BodyAttachment):
                if top.body not in body_idx:
                    refs_ok = False
                    probs.append((f"lines[{i}].top.body", f"unknown body {top.body!r} (known bodies: {known_bodies})"))
                else:
                    k = body_idx[top.body]
                    b = bodies[k]
                    if not isinstance(b, RigidBody) or b.aft_tow_point is None:
                        refs_ok = False
                        why = ("is a point body (only fish/depressor bodies have an aft tow point)"
                               if not isinstance(b, RigidBody) else f"has no aft_tow_point (set bodies[{k}].aft_tow_point)")
                        probs.append((f"lines[{i}].top.body",
                                      f"a line can only hang from a body's aft_tow_point, but body {top.body!r} {why}"))
            else:
                roots.append(i)
            bb = ln.bottom_body
            if bb is not None:
                if bb not in body_idx:
                    refs_ok = False
                    probs.append((f"lines[{i}].bottom.body", f"unknown body {bb!r} (known bodies: {known_bodies})"))
                else:
                    bottom_of.setdefault(bb, []).append(i)

        for k, b in enumerate(bodies):
            if body_idx.get(b.name) != k:
                continue
            users = bottom_of.get(b.name, [])
            if not users:
                refs_ok = False
                probs.append((f"bodies[{k}].name", f"body {b.name!r} is not the bottom of any line "
                                                   f"(each body must be the bottom of exactly one line)"))
            for j in users[1:]:
                refs_ok = False
                probs.append((f"lines[{j}].bottom.body",
                              f"body {b.name!r} is already the bottom of line {lines[users[0]].name!r} "
                              f"(a body is the bottom of exactly one line)"))

        if not roots:
            refs_ok = False
            probs.append(("lines", 'exactly one line must have top = "vessel" (got none)'))
        for i in roots[1:]:
            refs_ok = False
            probs.append((f"lines[{i}].top", f'only one line may have top = "vessel"; line '
                                             f'{lines[roots[0]].name!r} already does'))

        if refs_ok and not probs:
            # every line must reach the vessel through its parents (no cycles)
            def parent(ln: Line) -> str | None:
                if isinstance(ln.top, JunctionAttachment):
                    return ln.top.line
                if isinstance(ln.top, SpliceAttachment):
                    return ln.top.splice
                if isinstance(ln.top, BodyAttachment):
                    return lines[bottom_of[ln.top.body][0]].name
                return None

            for i, ln in enumerate(lines):
                seen = [ln.name]
                cur = ln
                while True:
                    p = parent(cur)
                    if p is None:
                        break
                    if p in seen:
                        cyc = " -> ".join(seen[seen.index(p):] + [p])
                        probs.append((f"lines[{i}].top", f"line {ln.name!r} is not connected to the vessel "
                                                         f"(cycle: {cyc}); the lines must form a tree rooted "
                                                         f"at the vessel"))
                        break
                    seen.append(p)
                    cur = lines[line_idx[p]]

        if not probs:
            for i, ln in enumerate(lines):
                if isinstance(ln.segments, tuple):
                    d = self._junction_distances(ln.name)
                    n = len(d) + 1
                    if len(ln.segments) != n:
                        where = (f" (junctions at {', '.join(f'{x:g}' for x in d)} m from its top)" if d else
                                 " (no junctions on it)")
                        probs.append((f"lines[{i}].segments",
                                      f"must list one count per span: line {ln.name!r} has {n} span"
                                      f"{'s' if n != 1 else ''}{where} (got {len(ln.segments)} entries)"))
        if self.sea is not None and self.vessel.model is None and self.vessel.rao_file is None:
            probs.append(("sea", "a sea moves the tow point through the vessel: set vessel.model (a preset: "
                                 "'coastal_survey', 'research_vessel') or vessel.rao_file"))
        if (self.vessel.rao_file is not None or self.vessel.model is not None) and self.sea is None \
                and self.vessel.motion_file is None:
            probs.append(("vessel.model", "a vessel RAO model needs a [sea] section"))
        if not probs and self.winch is not None:
            roots_names = [ln.name for ln in lines if ln.top_kind == "vessel"]
            wl = self.winch.line or (roots_names[0] if roots_names else None)
            if wl not in line_idx:
                probs.append(("winch.line", f"unknown line {wl!r}; known lines: {known_lines}"))
            else:
                ln = lines[line_idx[wl]]
                if ln.top_kind != "vessel":
                    probs.append(("winch.line", f"the winch must sit at the top of a line attached to the vessel "
                                                f"(line {wl!r} hangs from {ln.top_kind})"))
                elif self._junction_distances(wl):
                    d = min(self._junction_distances(wl))
                    probs_d = ln.length - d
                    if self.winch.min_length is not None and self.winch.min_length <= probs_d:
                        probs.append(("winch.min_length",
                                      f"line {wl!r} carries a junction {d:g} m below its top: min_length must "
                                      f"be > {probs_d:g} m so the winch never reels in past it "
                                      f"(got {self.winch.min_length!r})"))
                if self.winch.max_length is not None and self.winch.max_length < ln.length:
                    probs.append(("winch.max_length", f"must be >= the initial length {ln.length:g} m "
                                                      f"(got {self.winch.max_length!r})"))
                if self.winch.min_length is not None and self.winch.min_length > ln.length:
                    probs.append(("winch.min_length", f"must be <= the initial length {ln.length:g} m "
                                                      f"(got {self.winch.min_length!r})"))
        if probs:
            _problems(*probs)
        return self

    @model_validator(mode="after")
    def _check_solver_support(self):
        """What only some time integrations support, refused here rather than at run time."""
        probs: list[tuple[str, str]] = []
        method = self.solver.method
        if method != "houbolt":
            for fld in ("compensator", "winch"):
                if getattr(self, fld) is not None:
                    probs.append(("solver.method", f"{method!r} cannot simulate a {fld} (only \"houbolt\" models "
                                                   f"the actuators); use \"houbolt\" or remove [{fld}]"))
            if self.solver.settle_time > 0:
                probs.append(("solver.settle_time", f"must be 0 with solver.method = {method!r} (the dynamic "
                                                    f"settle runs with \"houbolt\" only; got {self.solver.settle_time:g})"))
        if method in ("generalized_alpha", "newmark") and self.sea is not None and self.sea.orbital_velocities:
            probs.append(("sea.orbital_velocities", f"not supported by solver.method = {method!r} (use \"houbolt\")"))
        total = sum(sum(ln.segments) if isinstance(ln.segments, tuple) else ln.segments for ln in self.lines)
        if total > MAX_SEGMENTS:
            probs.append(("lines", f"{total} segments in all: at most {MAX_SEGMENTS} per scene — {_SEGMENTS_WHY}"))
        if probs:
            _problems(*probs)
        return self

    # ---------------------------------------------------------------- lookups
    @property
    def source_dir(self) -> str | None:
        """Folder against which relative file paths (time series) resolve; None = working directory."""
        return self._source_dir

    def line(self, name: str) -> Line:
        for ln in self.lines:
            if ln.name == name:
                return ln
        raise KeyError(f"no line named {name!r} (lines: {', '.join(repr(l.name) for l in self.lines)})")

    def body(self, name: str) -> RigidBody | PointBody:
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(f"no body named {name!r} (bodies: {', '.join(repr(b.name) for b in self.bodies) or 'none'})")

    def _junction_distances(self, line_name: str) -> list[float]:
        return sorted({ln.top.distance for ln in self.lines
                       if isinstance(ln.top, JunctionAttachment) and ln.top.line == line_name})

    def junctions(self, line_name: str) -> list[float]:
        """Sorted, unique distances (m from the top end) of the junctions on a line."""
        self.line(line_name)
        return self._junction_distances(line_name)

    def children(self, line_name: str) -> list[Line]:
        """Lines whose top is a junction on ``line_name`` (sorted by distance)."""
        self.line(line_name)
        kids = [ln for ln in self.lines if isinstance(ln.top, JunctionAttachment) and ln.top.line == line_name]
        return sorted(kids, key=lambda ln: ln.top.distance)

    def span_segments(self, line_name: str) -> list[int]:
        """Segments per span of a line (top end first), given the junctions on it."""
        return self.line(line_name).span_segments(self._junction_distances(line_name))

    @property
    def root_line(self) -> Line:
        """The line hanging from the vessel."""
        return next(ln for ln in self.lines if ln.top_kind == "vessel")

    def body_line(self, body_name: str) -> Line:
        """The line whose bottom is the body."""
        self.body(body_name)
        return next(ln for ln in self.lines if ln.bottom_body == body_name)

    def tail_lines(self, body_name: str) -> list[Line]:
        """Lines hanging from the body's aft tow point (series tows)."""
        self.body(body_name)
        return [ln for ln in self.lines if isinstance(ln.top, BodyAttachment) and ln.top.body == body_name]

    def lines_top_down(self) -> list[Line]:
        """All lines, each after the line (or body's line) it hangs from, starting at the vessel."""
        order: list[Line] = []
        queue = [self.root_line]
        while queue:
            ln = queue.pop(0)
            order.append(ln)
            queue += self.children(ln.name)
            if ln.bottom_body is not None:
                queue += self.tail_lines(ln.bottom_body)
        return order

    # ---------------------------------------------------------------- export / variants
    def to_dict(self) -> dict:
        """Plain dict (lists, floats, strings) equivalent to the TOML file; ``load_scene`` accepts it."""
        return _clean(self.model_dump(mode="json"))

    def to_toml(self) -> str:
        """TOML text that loads back to an equal scene."""
        return dumps_toml(self.to_dict())

    def save(self, path) -> Path:
        """Write the scene as TOML."""
        p = Path(path)
        p.write_text(self.to_toml(), encoding="utf-8")
        return p

    def with_overrides(self, overrides: Mapping[str, Any] | None = None, /, **kw: Any) -> "Scene":
        """New validated scene with dotted-path overrides, e.g. ``{"solver.dt": 0.01, "vessel.speed": 2.0}``.

        Paths: ``a.b.c``; list items by index ``lines[0].length`` (or ``lines.0.length``) or by name
        ``lines.primary.length`` / ``bodies[fish].mass``. Keyword arguments may use ``__`` for ``.``
        (``solver__dt=0.01``). A value of ``None`` removes the key (back to its default)."""
        items: dict[str, Any] = {}
        if overrides is not None:
            if not isinstance(overrides, Mapping):
                raise SceneError(f"overrides must be a mapping of dotted paths to values (got {_short(overrides)})")
            items.update(overrides)
        items.update({k.replace("__", "."): v for k, v in kw.items()})
        # only the fields the user set (defaults re-apply on validation), so "was solver.dt given?"
        # survives overrides (towenv.fidelity selects what the user did not fix)
        data = _clean(self.model_dump(mode="json", exclude_unset=True))
        probs = []
        for key, value in items.items():
            try:
                _set_path(data, str(key), copy.deepcopy(value))
            except (KeyError, IndexError, TypeError, ValueError) as exc:
                probs.append((f"override {key!r}", str(exc.args[0]) if exc.args else "invalid path"))
        if probs:
            raise SceneError(probs)
        return _validate(data, self._source_dir, None)


from .loading import _validate  # noqa: E402  (circular: used inside methods only)
