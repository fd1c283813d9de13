"""Standard plots of a :class:`towenv.Result` (matplotlib, Agg backend; each function writes one PNG).

>>> from towenv import plots
>>> plots.side_view(res, "side_view.png")          # cable shapes in along-track coordinates
>>> plots.save_all(res, "out/", discard=30.0)       # all five plots

Every function takes the result, the output path and optional ``discard`` (s, the start-up window,
shaded in time plots and dropped from spectra). The side and plan views use the mean (oscillation-free)
tow-point path; pass it as ``track=(positions (n,3), heading (n,))`` (e.g. from
``Simulator.path.mean_path(res.t)``) or let :func:`estimate_track` reconstruct it from the record.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["estimate_track", "side_view", "plan_view", "body_motion", "tensions", "psd", "save_all", "PLOTS"]

_DPI = 110


def _plt():
    import matplotlib
    if matplotlib.get_backend().lower() != "agg":
        try:
            matplotlib.use("Agg", force=True)
        except Exception:  # pragma: no cover
            pass
    import matplotlib.pyplot as plt
    return plt


def _save(fig, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    from .atomic import atomic_write
    try:
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=_DPI), mode=None)
    finally:
        _plt().close(fig)
    return path


def _shade(ax, result, discard):
    if discard and discard > 0 and len(result.t):
        ax.axvspan(result.t[0], min(discard, result.t[-1]), color="0.9", zorder=0, lw=0)


def _body_colors(names):
    cyc = ["tab:red", "tab:blue", "tab:green", "tab:orange", "tab:purple", "tab:brown", "tab:pink", "tab:olive"]
    return {n: cyc[i % len(cyc)] for i, n in enumerate(names)}


_MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*"]


# ---------------------------------------------------------------------------------------------------
# mean tow-point path
# ---------------------------------------------------------------------------------------------------
def _chord_heading(t, xy, window=10.0):
    """Heading of the track from chords spanning ``window`` seconds (robust to oscillations)."""
    n = len(t)
    if n < 2:
        return np.zeros(n)
    dtr = float(np.median(np.diff(t)))
    h = max(1, int(round(0.5 * window / dtr)))
    lo = np.clip(np.arange(n) - h, 0, n - 1)
    hi = np.clip(np.arange(n) + h, 0, n - 1)
    d = xy[hi] - xy[lo]
    span = np.maximum(t[hi] - t[lo], 1e-12)
    speed = np.linalg.norm(d, axis=1) / span
    psi = np.arctan2(d[:, 1], d[:, 0])
    ok = speed > 0.05                                   # below ~5 cm/s the chord is mostly oscillation
    if not ok.any():
        return np.zeros(n)
    idx = np.where(ok, np.arange(n), -1)
    idx = np.maximum.accumulate(idx)                    # hold the last good heading
    first = int(np.argmax(ok))
    idx[idx < 0] = first
    return np.unwrap(psi[idx])


def estimate_track(result):
    """Reconstruct the mean tow-point path ``(positions (n,3), heading (n,))`` from a Result.

    With two bodies at different along/across-track offsets the heading follows exactly from their
    recorded positions and surge/sway; otherwise from chords of the tow-point track. The mean position is
    then ``body position - (surge e_along + sway e_across + heave e_z)`` of the first body (exact given the
    heading), or a one-period-free chord midpoint of the tow point when there are no bodies."""
    t = np.asarray(result.t, float)
    tp = np.asarray(result.tow_point, float)
    names = list(result.bodies)
    psi = None
    if len(names) >= 2:
        best, spread = None, 0.0
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                a, b = result.bodies[names[i]], result.bodies[names[j]]
                ds = np.stack([a["surge"] - b["surge"], a["sway"] - b["sway"]], axis=1)
                m = float(np.median(np.linalg.norm(ds, axis=1)))
                if m > spread:
                    best, spread = (a, b, ds), m
        if best is not None and spread > 1.0:
            a, b, ds = best
            dp = (a["position"] - b["position"])[:, :2]
            # rotation taking (ds_along, ds_across) in track axes to dp in global axes
            psi = np.unwrap(np.arctan2(dp[:, 1], dp[:, 0]) - np.arctan2(ds[:, 1], ds[:, 0]))
    if psi is None:
        psi = _chord_heading(t, tp[:, :2])
    ea = np.stack([np.cos(psi), np.sin(psi), np.zeros_like(psi)], axis=1)
    ec = np.stack([-np.sin(psi), np.cos(psi), np.zeros_like(psi)], axis=1)
    if names:
        d = result.bodies[names[0]]
        mean = d["position"] - d["surge"][:, None] * ea - d["sway"][:, None] * ec
        mean = mean.copy()
        mean[:, 2] = d["position"][:, 2] - d["heave"]
    else:
        mean = tp.copy()
    return mean, psi


def _track(result, track):
    if track is None:
        return estimate_track(result)
    mean, psi = track
    return np.asarray(mean, float), np.asarray(psi, float)


def _snapshot_indices(n, count=12):
    return np.unique(np.linspace(0, n - 1, min(count, n)).round().astype(int))


# ---------------------------------------------------------------------------------------------------
# plots
# ---------------------------------------------------------------------------------------------------
def side_view(result, path, discard: float = 0.0, track=None, snapshots: int = 12, title: str | None = None):
    """Cable shapes in the vertical plane: along-track distance from the mean tow point (negative = astern)
    against z, ``snapshots`` instants over the run (earliest faint, latest dark), bodies as markers."""
    plt = _plt()
    from matplotlib import cm, colors
    mean, psi = _track(result, track)
    t = result.t
    idx = _snapshot_indices(len(t), snapshots)
    ea = np.stack([np.cos(psi), np.sin(psi)], axis=1)
    fig, ax = plt.subplots(figsize=(9, 6.2))
    base = plt.get_cmap("Blues")
    cmap = colors.LinearSegmentedColormap.from_list("blues_faded", base(np.linspace(0.25, 1.0, 64)))
    norm = colors.Normalize(vmin=t[idx[0]], vmax=t[idx[-1]] if idx[-1] != idx[0] else t[idx[0]] + 1)
    bcol = _body_colors(list(result.bodies))
    for k, i in enumerate(idx):
        frac = (k + 1) / len(idx)
        col = cmap(norm(t[i]))
        alpha = 0.25 + 0.75 * frac
        for ln, d in result.lines.items():
            p = d["positions"][i]
            along = (p[:, :2] - mean[i, :2]) @ ea[i]
            ax.plot(along, p[:, 2], "-", color=col, alpha=alpha, lw=1.0 + 0.8 * frac)
            ax.plot(along[1:-1], p[1:-1, 2], ".", color=col, alpha=alpha, ms=2.5)
        for j, (bn, d) in enumerate(result.bodies.items()):
            p = d["position"][i]
            along = float((p[:2] - mean[i, :2]) @ ea[i])
            ax.plot(along, p[2], _MARKERS[j % len(_MARKERS)], color=bcol[bn], alpha=alpha, ms=7,
                    mec="k", mew=0.5, label=bn if k == len(idx) - 1 else None)
    if result.tow_point is not None:
        i = idx[-1]
        tp = result.tow_point[i]
        ax.plot(float((tp[:2] - mean[i, :2]) @ ea[i]), tp[2], "k^", ms=8, label="tow point")
    ax.axhline(float(np.mean(mean[:, 2])), color="0.6", lw=0.6, ls=":")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("along-track distance from the mean tow point (m, negative = astern)")
    ax.set_ylabel("z (m, up)")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=9)
    sm = cm.ScalarMappable(norm=norm, cmap=cmap)
    sm.set_array([])
    fig.colorbar(sm, ax=ax, label="time (s)", shrink=0.8)
    ax.set_title(title or f"Side view: cable shapes, {len(idx)} instants over {t[0]:.0f}–{t[-1]:.0f} s")
    fig.tight_layout()
    return _save(fig, path)


def plan_view(result, path, discard: float = 0.0, track=None, title: str | None = None):
    """Horizontal x–y tracks of the tow point (and its mean path) and of every body; cables at the end."""
    plt = _plt()
    mean, _ = _track(result, track)
    fig, ax = plt.subplots(figsize=(9, 6.2))
    tp = result.tow_point
    if tp is not None:
        ax.plot(tp[:, 0], tp[:, 1], "-", color="k", lw=0.8, label="tow point")
    ax.plot(mean[:, 0], mean[:, 1], "--", color="0.5", lw=0.8, label="mean tow-point path")
    bcol = _body_colors(list(result.bodies))
    for j, (bn, d) in enumerate(result.bodies.items()):
        p = d["position"]
        ax.plot(p[:, 0], p[:, 1], "-", color=bcol[bn], lw=1.0, label=bn)
        ax.plot(p[-1, 0], p[-1, 1], _MARKERS[j % len(_MARKERS)], color=bcol[bn], mec="k", mew=0.5, ms=7)
        ax.plot(p[0, 0], p[0, 1], _MARKERS[j % len(_MARKERS)], color="none", mec=bcol[bn], mew=1.0, ms=7)
    for ln, d in result.lines.items():
        p = d["positions"][-1]
        ax.plot(p[:, 0], p[:, 1], "-", color="tab:cyan", lw=1.2, alpha=0.8)
    if tp is not None:
        ax.plot(tp[0, 0], tp[0, 1], "k^", mfc="none", ms=8)
        ax.plot(tp[-1, 0], tp[-1, 1], "k^", ms=8)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m, to port)")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=9)
    ax.set_title(title or "Plan view: tracks (hollow marker = start, filled = end, cyan = cables at end)")
    fig.tight_layout()
    return _save(fig, path)


def body_motion(result, path, discard: float = 0.0, title: str | None = None):
    """Heave, pitch and surge of every body against time (start-up window shaded)."""
    plt = _plt()
    t = result.t
    fig, axes = plt.subplots(3, 1, figsize=(10, 7.5), sharex=True)
    bcol = _body_colors(list(result.bodies))
    after = t >= discard if np.any(t >= discard) else np.ones(len(t), bool)
    for bn, d in result.bodies.items():
        # heave and surge about their mean after the start-up window (bodies sit tens of m apart)
        hm, sm = float(np.mean(d["heave"][after])), float(np.mean(d["surge"][after]))
        axes[0].plot(t, d["heave"] - hm, color=bcol[bn], lw=1.0, label=f"{bn} (mean {hm:.1f} m)")
        axes[1].plot(t, np.degrees(d["euler"][:, 1]), color=bcol[bn], lw=1.0, label=bn)
        axes[2].plot(t, d["surge"] - sm, color=bcol[bn], lw=1.0, label=f"{bn} (mean {sm:.1f} m)")
    labels = ["heave − mean (m)", "pitch (deg, + nose down)", "surge − mean (m)"]
    for ax, lab in zip(axes, labels):
        _shade(ax, result, discard)
        ax.set_ylabel(lab, fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8, ncol=max(1, len(result.bodies)))
    axes[2].legend(loc="upper right", fontsize=8, ncol=max(1, len(result.bodies)))
    axes[-1].set_xlabel("time (s)" + (" — grey: start-up window excluded from statistics" if discard else ""))
    fig.suptitle(title or "Body motions (heave/surge relative to the mean tow-point path, up/ahead positive)")
    fig.tight_layout()
    return _save(fig, path)


def tensions(result, path, discard: float = 0.0, title: str | None = None):
    """Tow-point tension and the top-segment tension of every line against time."""
    plt = _plt()
    t = result.t
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    if result.top_tension is not None:
        axes[0].plot(t, result.top_tension / 1e3, color="k", lw=1.0)
    axes[0].set_ylabel("tow-point tension (kN)")
    for ln, d in result.lines.items():
        axes[1].plot(t, d["tensions"][:, 0] / 1e3, lw=1.0, label=f"{ln} (top segment)")
    axes[1].set_ylabel("segment tension (kN)")
    axes[1].legend(loc="best", fontsize=9)
    for ax in axes:
        _shade(ax, result, discard)
        ax.grid(alpha=0.3)
        ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
    axes[-1].set_xlabel("time (s)" + (" — grey: start-up window" if discard else ""))
    fig.suptitle(title or "Tensions")
    fig.tight_layout()
    return _save(fig, path)


def psd(result, path, discard: float = 0.0, title: str | None = None):
    """Welch spectra (one-sided, rad/s) of heave and pitch of every body after the start-up window."""
    from .stats import welch_psd
    plt = _plt()
    w = result.window(discard)
    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    bcol = _body_colors(list(result.bodies))
    xmax = 0.0
    n = len(w.t)
    if n >= 16:
        dtr = float(np.median(np.diff(w.t)))
        nyq = math.pi / dtr
        # segments as long as possible while keeping >= ~4 half-overlapping ones (frequency resolution
        # matters more than variance for short deterministic-looking records)
        nperseg = max(16, 1 << int(math.floor(math.log2(max(16, n / 2.5)))))
        peaks = [0.0, 0.0]
        for bn, d in w.bodies.items():
            for k, (ax, x) in enumerate(((axes[0], d["heave"]), (axes[1], np.degrees(d["euler"][:, 1])))):
                om, S = welch_psd(np.asarray(x, float), dtr, nperseg=min(nperseg, n))
                if not np.any(S > 0):
                    continue
                ax.semilogy(om, S, color=bcol[bn], lw=1.0, label=bn)
                peaks[k] = max(peaks[k], float(S.max()))
                c = np.cumsum(S)
                xmax = max(xmax, float(om[min(len(om) - 1, np.searchsorted(c, 0.995 * c[-1]))]))
        xmax = min(nyq, max(2.0, 2.0 * xmax))
        axes[0].set_xlim(0, xmax)
        for ax, pk in zip(axes, peaks):
            if pk > 0:
                ax.set_ylim(pk * 1e-6, pk * 3.0)
        note = (f"Welch PSD over t = {w.t[0]:.0f}–{w.t[-1]:.0f} s "
                f"(segments of {min(nperseg, n) * dtr:.0f} s, Δω = {2 * math.pi / (min(nperseg, n) * dtr):.2f} rad/s)")
    else:
        note = "record after the start-up window too short for a spectrum"
        for ax in axes:
            ax.text(0.5, 0.5, note, ha="center", va="center", transform=ax.transAxes)
    axes[0].set_ylabel("heave PSD (m² s/rad)")
    axes[1].set_ylabel("pitch PSD (deg² s/rad)")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="best", fontsize=9)
    axes[-1].set_xlabel("ω (rad/s)")
    fig.suptitle(title or note)
    fig.tight_layout()
    return _save(fig, path)


def actuators(result, path, discard: float = 0.0, title: str | None = None):
    """Compensator stroke and stroke velocity, and/or winch payout speed and deployed length."""
    acts = getattr(result, "actuators", {}) or {}
    panels = [k for k in ("stroke", "stroke_velocity", "payout_speed", "deployed_length") if k in acts]
    if not panels:
        return None
    plt = _plt()
    labels = {"stroke": "compensator stroke (m)", "stroke_velocity": "stroke velocity (m/s)",
              "payout_speed": "winch payout speed (m/s)", "deployed_length": "deployed length (m)"}
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.2 * len(panels)), sharex=True, squeeze=False)
    for ax, k in zip(axes[:, 0], panels):
        ax.plot(result.t, acts[k], lw=0.9)
        ax.set_ylabel(labels[k])
        ax.grid(alpha=0.3)
        _shade(ax, result, discard)
    axes[-1, 0].set_xlabel("t (s)")
    fig.suptitle(title or "Actuators")
    return _save(fig, path)


#: file name -> plotting function, as written by :func:`save_all`
PLOTS = {"side_view.png": side_view, "plan_view.png": plan_view, "body_motion.png": body_motion,
         "tensions.png": tensions, "psd.png": psd, "actuators.png": actuators}


def save_all(result, folder, discard: float = 0.0, track=None) -> list[Path]:
    """Write all standard plots into ``folder``; returns their paths."""
    folder = Path(folder)
    track = _track(result, track)
    out = []
    for fname, fn in PLOTS.items():
        kw = {"track": track} if fn in (side_view, plan_view) else {}
        p = fn(result, folder / fname, discard=discard, **kw)
        if p is not None:
            out.append(p)
    return out
