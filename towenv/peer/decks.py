"""Scenes shared by the MoorDyn cross-checks, the speed/accuracy study and the stability map.

* :func:`shared_deck` — the verification "peer deck" (verification.md) towed at 2 m/s with a 1 m
  tow-point heave at 8 s (the V9 Δt-convergence case), buildable identically in MoorDyn;
* :func:`with_segment_factor` — the same scene with every line's segment count scaled;
* :func:`series_tow` — a series multi-tow with any number of bodies (cables in series) built from the
  embedded ``series_multitow`` scene (thesis Table 4.2) by repeating its last cable + fish.
"""
from __future__ import annotations

import copy
import math

from ..scene import Solver, load_scene

#: keyword overrides of :func:`shared_deck` / :func:`series_tow` that go to ``[solver]`` (every field of the
#: solver schema: ``dt``, ``rho_inf``, ``planar``, ...); other keys are dotted scene paths
SOLVER_KEYS = tuple(Solver.model_fields)


def shared_deck(segments: int = 20, speed: float = 2.0, heave: float = 1.0, period: float = 8.0,
                ramp: dict | None = None, EA_factor: float = 1.0, **overrides):
    """The peer deck towed at ``speed`` with a vertical tow-point sinusoid (amplitude ``heave``, m;
    ``period``, s). ``ramp``: the start-up ramp table (default: towenv's, half-cosine 12 s);
    ``EA_factor`` scales the cable stiffness; ``overrides``: dotted scene paths (``{"solver.dt": 0.01}``)
    or solver keys (``dt=0.01``)."""
    sc = load_scene("peer_deck")
    ov = {"vessel.speed": float(speed), "lines[0].segments": int(segments),
          "lines[0].EA": float(sc.lines[0].EA * EA_factor)}
    if heave:
        ov["vessel.excitation"] = [dict(type="sinusoid", axis="z", amplitude=float(heave), period=float(period))]
    if ramp is not None:
        ov["vessel.ramp"] = dict(ramp)
    for k, v in overrides.items():
        ov["solver." + k if k in SOLVER_KEYS else k] = v
    return sc.with_overrides(ov)


def with_segment_factor(scene, factor: float):
    """``scene`` with every line's segment count (or each span's) multiplied by ``factor`` (rounded, ≥ 1)."""
    sc = load_scene(scene)
    if factor == 1:
        return sc
    d = sc.to_dict()
    for ln in d["lines"]:
        s = ln["segments"]
        if isinstance(s, (list, tuple)):
            ln["segments"] = [max(1, int(round(k * factor))) for k in s]
        else:
            ln["segments"] = max(1, int(round(s * factor)))
    return load_scene(d)


def total_segments(scene) -> int:
    sc = load_scene(scene)
    out = 0
    for ln in sc.lines:
        s = ln.segments
        out += sum(s) if isinstance(s, (list, tuple)) else int(s)
    return out


def axial_cfl_step(scene) -> float:
    """The explicit (axial CFL) step limit l/c_L, minimised over the segments (model.md 8.2)."""
    sc = load_scene(scene)
    best = math.inf
    for ln in sc.lines:
        spans = ln.span_segments(_junctions(sc, ln.name))
        b = ln.span_bounds(_junctions(sc, ln.name))
        c = math.sqrt(ln.EA / ln.mass_per_length)
        for i, n in enumerate(spans):
            best = min(best, (b[i + 1] - b[i]) / n / c)
    return best


def _junctions(sc, name):
    return [ln.top.distance for ln in sc.lines if ln.top_kind == "line" and ln.top.line == name]


def series_tow(n_bodies: int = 4, **overrides):
    """A series multi-tow with ``n_bodies`` bodies (``n_bodies`` cables in series), built from the
    embedded ``series_multitow`` (ship – primary – depressor – cable – fish2 – cable – fish1): for
    ``n_bodies`` > 3, fish1 gets an aft tow point (the same tail attachment as fish2) and further
    30 m / 3-segment cables with copies of fish1 (``fish_t1``, ``fish_t2``, ...) are appended; for
    ``n_bodies`` < 3 the tail is cut. ``overrides`` as in :func:`shared_deck`."""
    if n_bodies < 1:
        raise ValueError(f"n_bodies: must be >= 1 (got {n_bodies})")
    d = load_scene("series_multitow").to_dict()
    d["name"] = f"series_tow_{n_bodies}"
    lines = d["lines"]
    bodies = d["bodies"]
    order = ["depressor", "fish2", "fish1"]
    if n_bodies < 3:
        keep = order[:n_bodies]
        d["bodies"] = [b for b in bodies if b["name"] in keep]
        d["lines"] = [ln for ln in lines if ln["bottom"].get("body") in keep]
        for b in d["bodies"]:
            if b["name"] == keep[-1]:
                b.pop("aft_tow_point", None)
    else:
        fish2 = next(b for b in bodies if b["name"] == "fish2")
        fish1 = next(b for b in bodies if b["name"] == "fish1")
        tail = next(ln for ln in lines if ln["bottom"].get("body") == "fish1")
        prev = "fish1"
        for k in range(n_bodies - 3):
            name = f"fish_t{k + 1}"
            nb = copy.deepcopy(fish1)
            nb["name"] = name
            pb = next(b for b in d["bodies"] if b["name"] == prev)
            pb["aft_tow_point"] = list(fish2["aft_tow_point"])
            d["bodies"].append(nb)
            nl = copy.deepcopy(tail)
            nl["name"] = f"sub_cable_t{k + 1}"
            nl["top"] = {"body": prev}
            nl["bottom"] = {"body": name}
            d["lines"].append(nl)
            prev = name
    sc = load_scene(d)
    if overrides:
        sc = sc.with_overrides({("solver." + k if k in SOLVER_KEYS else k): v for k, v in overrides.items()})
    return sc
