"""Run summaries: motion amplitudes, rate-limit checks, tensions and solver statistics of a :class:`Result`.

>>> res = towenv.simulate("two_part_tow_1", 120)
>>> s = summarize(res, discard=30.0)          # dict of plain floats/ints (JSON-ready)
>>> s["bodies"]["fish"]["significant_amplitude"]["heave"]
>>> print(summary_markdown(s))

Conventions: significant amplitude = ``2 sqrt(m0)`` = 2 x standard deviation of the record after the
start-up window (:func:`towenv.stats.significant_amplitude`); angles in degrees (pitch positive nose
down); depth positive downward (``-z``); rates in the units of thesis Table 6.1
(:data:`towenv.stats.RATE_LIMITS`: m/s for surge/sway/heave, deg/s for roll/pitch/yaw).
"""
from __future__ import annotations

import math

import numpy as np

from .stats import RATE_LIMITS, rate_limit_check, significant_amplitude

__all__ = ["summarize", "summary_markdown", "default_discard", "timeseries_table", "write_timeseries_csv",
           "SLACK_TENSION"]

#: a segment counts as slack when its tension is at or below this value (N)
SLACK_TENSION = 0.0

_TRANSLATIONS = ("heave", "surge", "sway")
_ROTATIONS = ("roll", "pitch", "yaw")          # euler / omega columns 0, 1, 2


def default_discard(scene, duration: float) -> float:
    """Start-up window to drop before statistics: ``max(ramp, 0.25 duration)``.

    The ramp length is the ramp ``duration`` for a half-cosine ramp, three time constants for an
    exponential one (95 % of the excitation) and 0 for none."""
    ramp = 0.0
    vessel = getattr(scene, "vessel", None)
    r = getattr(vessel, "ramp", None)
    if r is not None:
        kind = getattr(r, "type", "half_cosine")
        d = float(getattr(r, "duration", 0.0) or 0.0)
        ramp = 0.0 if kind == "none" else (3.0 * d if kind == "exponential" else d)
    return float(max(ramp, 0.25 * float(duration)))


def _f(x):
    """Plain float, or None when not finite (JSON has no NaN/inf)."""
    x = float(x)
    return x if math.isfinite(x) else None


def _rates(d: dict, t: np.ndarray) -> dict:
    """Motion rates of one body in the units of RATE_LIMITS (translations relative to the mean path)."""
    out = {}
    for k in _TRANSLATIONS:
        x = np.asarray(d[k], float)
        out[k] = np.gradient(x, t) if x.size > 1 else np.zeros_like(x)
    om = np.asarray(d["omega"], float)
    for i, k in enumerate(_ROTATIONS):
        out[k] = om[:, i]                                        # rad/s (rate_limit_check converts)
    return out


def summarize(result, discard: float = 0.0) -> dict:
    """Statistics of ``result`` from ``t >= discard`` on, as a JSON-ready dict.

    Keys: ``scene``, ``duration``, ``discard``, ``window`` ([t0, t1] s), ``samples``,
    ``bodies[name]`` (``mean_depth`` m, ``mean_pitch`` deg, ``significant_amplitude`` {heave, surge,
    sway m; roll, pitch, yaw deg}, ``std``, ``rates`` {motion: rms, max_abs, limit, unit,
    fraction_over, rms_ok, peak_ok}), ``top_tension`` {min, mean, max N}, ``lines[name]``
    (``top_segment`` {min, mean, max}, ``max_segment_tension``, ``bottom_segment_max``, ``slack_segments``
    (segments that were slack at least once), ``slack_samples`` (segment-samples at zero tension),
    ``slack_fraction``), ``solver`` (real_time_factor, steps, mean_iterations, max_iterations,
    step_cuts, wall_time_s, dt). Non-finite numbers become ``None``.
    """
    t_all = np.asarray(result.t, float)
    if t_all.size == 0:
        raise ValueError("empty result: nothing to summarize")
    discard = float(discard)
    w = result.window(discard)
    t = np.asarray(w.t, float)
    if t.size < 2:
        raise ValueError(f"discard = {discard:g} s leaves fewer than 2 samples (record ends at t = {t_all[-1]:g} s)")

    out: dict = {
        "scene": result.meta.get("scene"),
        "duration": _f(result.meta.get("duration", t_all[-1] - t_all[0])),
        "discard": discard,
        "window": [_f(t[0]), _f(t[-1])],
        "samples": int(t.size),
        "bodies": {},
        "top_tension": None,
        "lines": {},
        "solver": {},
    }

    for name, d in w.bodies.items():
        pos = np.asarray(d["position"], float)
        eul_deg = np.degrees(np.asarray(d["euler"], float))
        series = {k: np.asarray(d[k], float) for k in _TRANSLATIONS}
        series.update({k: eul_deg[:, i] for i, k in enumerate(_ROTATIONS)})
        rates = _rates(d, t)
        checks = rate_limit_check(rates, angular_unit="rad/s")
        rate_out = {}
        for k, chk in checks.items():
            r = rates[k]
            if RATE_LIMITS[k][1] == "deg/s":
                r = np.degrees(r)
            rms = float(np.sqrt(np.mean(r * r)))
            rate_out[k] = {"rms": _f(rms), "max_abs": _f(chk.max_abs), "limit": chk.limit, "unit": chk.unit,
                           "fraction_over": _f(chk.fraction_over), "rms_ok": bool(rms <= chk.limit),
                           "peak_ok": bool(chk.ok)}
        out["bodies"][name] = {
            "mean_depth": _f(-np.mean(pos[:, 2])),
            "mean_position": [_f(v) for v in pos.mean(axis=0)],
            "mean_pitch": _f(np.mean(eul_deg[:, 1])),
            "mean_roll": _f(np.mean(eul_deg[:, 0])),
            "mean_surge": _f(np.mean(series["surge"])),
            "mean_sway": _f(np.mean(series["sway"])),
            "significant_amplitude": {k: _f(significant_amplitude(v)) for k, v in series.items()},
            "std": {k: _f(np.std(v)) for k, v in series.items()},
            "rates": rate_out,
        }

    if w.top_tension is not None:
        tt = np.asarray(w.top_tension, float)
        out["top_tension"] = {"min": _f(tt.min()), "mean": _f(tt.mean()), "max": _f(tt.max())}

    for name, d in w.lines.items():
        T = np.asarray(d["tensions"], float)                    # (n, segments), top first (NaN-padded
        valid = np.isfinite(T)                                  # for a winch line whose node count changes)
        slack = valid & (T <= SLACK_TENSION)
        last = np.array([row[np.isfinite(row)][-1] if np.isfinite(row).any() else np.nan for row in T])
        out["lines"][name] = {
            "segments": int(np.max(valid.sum(axis=1))) if valid.size else 0,
            "top_segment": {"min": _f(np.nanmin(T[:, 0])), "mean": _f(np.nanmean(T[:, 0])),
                            "max": _f(np.nanmax(T[:, 0]))},
            "bottom_segment_max": _f(np.nanmax(last)),
            "max_segment_tension": _f(np.nanmax(T)),
            "min_segment_tension": _f(np.nanmin(T)),
            "slack_segments": int(np.count_nonzero(slack.any(axis=0))),
            "slack_samples": int(np.count_nonzero(slack)),
            "slack_fraction": _f(np.count_nonzero(slack) / max(np.count_nonzero(valid), 1)),
        }
    acts = getattr(w, "actuators", {}) or {}
    if acts:
        out["actuators"] = {}
        if "stroke" in acts:
            z = np.asarray(acts["stroke"], float)
            out["actuators"]["compensator"] = {
                "stroke_significant_amplitude": _f(2 * np.std(z)), "stroke_min": _f(z.min()),
                "stroke_max": _f(z.max()), "stroke_velocity_rms": _f(np.sqrt(np.mean(np.square(acts["stroke_velocity"])))),
                "end_stop_hits": result.meta.get("end_stop_hits"),
            }
        if "payout_speed" in acts:
            out["actuators"]["winch"] = {
                "length_start": _f(acts["deployed_length"][0]), "length_end": _f(acts["deployed_length"][-1]),
                "payout_speed_rms": _f(np.sqrt(np.mean(np.square(acts["payout_speed"])))),
            }

    m = result.meta
    out["solver"] = {k: (_f(m[k]) if isinstance(m.get(k), float) else m.get(k))
                     for k in ("dt", "real_time_factor", "wall_time_s", "steps", "mean_iterations",
                               "max_iterations", "step_cuts") if k in m}
    return out


# ---------------------------------------------------------------------------------------------------
# Markdown
# ---------------------------------------------------------------------------------------------------
def _fmt(x, digits: int = 3) -> str:
    if x is None:
        return "n/a"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return str(x)
    x = float(x)
    if x == 0:
        return "0"
    a = abs(x)
    if a >= 1000 or a < 1e-3:
        return f"{x:.4g}"
    return f"{x:.{max(0, digits - 1 - int(math.floor(math.log10(a))))}f}"


def _table(header: list[str], rows: list[list[str]], align_first_left: bool = True) -> list[str]:
    widths = [max(len(str(r[i])) for r in [header] + rows) for i in range(len(header))]

    def line(cells):
        parts = [str(c).ljust(widths[i]) if (i == 0 and align_first_left) else str(c).rjust(widths[i])
                 for i, c in enumerate(cells)]
        return "| " + " | ".join(parts) + " |"

    sep = "|" + "|".join(("-" * (w + 1) + ("-" if i == 0 else ":")) for i, w in enumerate(widths)) + "|"
    return [line(header), sep] + [line(r) for r in rows]


def summary_markdown(summary: dict, title: str | None = None) -> str:
    """Markdown report of a :func:`summarize` dict (tables aligned for reading as plain text too)."""
    s = summary
    name = title or s.get("scene") or "run"
    out = [f"# towenv run: {name}", ""]
    dt = s.get("solver", {}).get("dt")
    w0, w1 = s["window"]
    out.append(f"Simulated {_fmt(s.get('duration'))} s" + (f" (dt = {_fmt(dt)} s)" if dt else "")
               + f"; statistics over t = {_fmt(w0)}–{_fmt(w1)} s ({s['samples']} samples, first "
               f"{_fmt(s['discard'])} s discarded as start-up).")
    out.append("")

    bodies = s.get("bodies", {})
    if bodies:
        names = list(bodies)
        rows = []
        rows.append(["mean depth (m)"] + [_fmt(bodies[b]["mean_depth"]) for b in names])
        rows.append(["mean pitch (deg, + nose down)"] + [_fmt(bodies[b]["mean_pitch"]) for b in names])
        rows.append(["mean surge behind tow point (m)"]
                    + [_fmt(-bodies[b]["mean_surge"]) if bodies[b]["mean_surge"] is not None else "n/a"
                       for b in names])
        for k, unit in (("heave", "m"), ("surge", "m"), ("sway", "m"), ("roll", "deg"), ("pitch", "deg"),
                        ("yaw", "deg")):
            rows.append([f"{k} significant amplitude ({unit})"]
                        + [_fmt(bodies[b]["significant_amplitude"][k]) for b in names])
        for k in ("heave", "pitch"):
            lim, unit = RATE_LIMITS[k]
            rows.append([f"{k} rate RMS ({unit}; limit {_fmt(lim)})"]
                        + [f"{_fmt(bodies[b]['rates'][k]['rms'])} {'ok' if bodies[b]['rates'][k]['rms_ok'] else 'OVER'}"
                           for b in names])
            rows.append([f"{k} rate peak ({unit}), % time over limit"]
                        + [f"{_fmt(bodies[b]['rates'][k]['max_abs'])}, "
                           f"{_fmt(100 * (bodies[b]['rates'][k]['fraction_over'] or 0.0), 2)} %" for b in names])
        out += ["## Bodies", ""] + _table(["quantity"] + names, rows) + [""]
        out.append("Significant amplitude = 2·std (2√m0) of the record after the start-up window; "
                   "heave/surge/sway relative to the mean tow-point path. Rate limits: thesis Table 6.1.")
        out.append("")

    rows = []
    tt = s.get("top_tension")
    if tt:
        rows.append(["top tension (tow point)", _fmt(tt["min"] / 1e3), _fmt(tt["mean"] / 1e3), _fmt(tt["max"] / 1e3),
                     "", ""])
    for ln, d in s.get("lines", {}).items():
        ts = d["top_segment"]
        rows.append([f"line {ln}: top segment", _fmt(ts["min"] / 1e3), _fmt(ts["mean"] / 1e3), _fmt(ts["max"] / 1e3),
                     _fmt(d["max_segment_tension"] / 1e3), f"{d['slack_segments']}/{d['segments']} "
                     f"({_fmt(100 * d['slack_fraction'], 2)} %)"])
    if rows:
        out += ["## Tensions (kN)", ""]
        out += _table(["", "min", "mean", "max", "max any segment", "slack segments (% samples)"], rows)
        out += ["", "Slack: segments at zero tension at least once / all segments, and the share of "
                    "segment-samples at zero tension.", ""]

    acts = s.get("actuators", {})
    if acts:
        rows = []
        c = acts.get("compensator")
        if c:
            rows += [["compensator stroke, significant amplitude (m)", _fmt(c["stroke_significant_amplitude"])],
                     ["compensator stroke min / max (m)", f"{_fmt(c['stroke_min'])} / {_fmt(c['stroke_max'])}"],
                     ["stroke velocity RMS (m/s)", _fmt(c["stroke_velocity_rms"])],
                     ["end-stop hits (whole run)", _fmt(c["end_stop_hits"])]]
        wn = acts.get("winch")
        if wn:
            rows += [["winch: deployed length start / end (m)", f"{_fmt(wn['length_start'])} / {_fmt(wn['length_end'])}"],
                     ["winch payout speed RMS (m/s)", _fmt(wn["payout_speed_rms"])]]
        out += ["## Actuators", ""] + _table(["", "value"], rows) + [""]

    sv = s.get("solver", {})
    if sv:
        rows = [["real-time factor", _fmt(sv.get("real_time_factor"))],
                ["wall time (s)", _fmt(sv.get("wall_time_s"))],
                ["steps", _fmt(sv.get("steps"))],
                ["mean Newton iterations / step", _fmt(sv.get("mean_iterations"))],
                ["max Newton iterations", _fmt(sv.get("max_iterations"))],
                ["step cuts", _fmt(sv.get("step_cuts"))]]
        out += ["## Solver", ""] + _table(["statistic", "value"], rows) + [""]
    return "\n".join(out)


# ---------------------------------------------------------------------------------------------------
# CSV time series
# ---------------------------------------------------------------------------------------------------
def timeseries_table(result) -> tuple[list[str], np.ndarray]:
    """Column names and an (n, columns) array: ``t``, tow point xyz, top tension; per body position
    xyz, heave/surge/sway (m), roll/pitch/yaw (deg); per line top and bottom segment tension (N)."""
    cols: list[str] = ["t", "tow_x", "tow_y", "tow_z", "top_tension"]
    n = len(result.t)
    data = [np.asarray(result.t, float)]
    tp = np.full((n, 3), np.nan) if result.tow_point is None else np.asarray(result.tow_point, float)
    data += [tp[:, 0], tp[:, 1], tp[:, 2]]
    data.append(np.full(n, np.nan) if result.top_tension is None else np.asarray(result.top_tension, float))
    for b, d in result.bodies.items():
        p = np.asarray(d["position"], float)
        e = np.degrees(np.asarray(d["euler"], float))
        cols += [f"{b}_x", f"{b}_y", f"{b}_z", f"{b}_heave", f"{b}_surge", f"{b}_sway",
                 f"{b}_roll_deg", f"{b}_pitch_deg", f"{b}_yaw_deg"]
        data += [p[:, 0], p[:, 1], p[:, 2], d["heave"], d["surge"], d["sway"], e[:, 0], e[:, 1], e[:, 2]]
    for ln, d in result.lines.items():
        T = np.asarray(d["tensions"], float)
        cols += [f"{ln}_top_tension", f"{ln}_bottom_tension"]
        data += [T[:, 0], T[:, -1]]
    return cols, np.column_stack([np.asarray(c, float) for c in data])


def write_timeseries_csv(result, path):
    """Write :func:`timeseries_table` as a CSV file with a header row."""
    from pathlib import Path
    cols, arr = timeseries_table(result)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    from .atomic import atomic_write
    atomic_write(path, lambda f: np.savetxt(f, arr, delimiter=",", header=",".join(cols), comments="", fmt="%.8g"),
                 mode="wb")
    return path
