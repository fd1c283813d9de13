"""Shared helpers of the validation cases: running scenes (keeping the record when a run diverges),
harmonic fits, motion-rate checks, tables and figures.

Every number a case reports is computed here or in the case modules from simulator output; the published
values the cases compare against are constants in :mod:`towenv.validation.reference`, each with its source.
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..core.run import Recorder
from ..core.simulator import Simulator
from ..errors import SimulationDivergence

__all__ = ["RunOutcome", "run_scene", "harmonic", "amplitude", "Table", "Figure", "fmt", "pct", "Progress",
           "motion_rates", "rate_exceedance", "savefig", "scene_dict", "CaseContext"]


# ---------------------------------------------------------------------------------------------------
# running
# ---------------------------------------------------------------------------------------------------
@dataclass
class RunOutcome:
    """A (possibly partial) run: ``result`` holds the record up to the failure when ``error`` is set."""
    result: object
    error: str | None
    wall: float
    failed_at: float | None = None
    stats: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.error is None


def run_scene(scene, duration: float, record_interval: float | None = None, **overrides) -> RunOutcome:
    """Like :func:`towenv.simulate`, but a :class:`~towenv.SimulationDivergence` does not discard the
    record: the result up to the last good step is returned with the error message."""
    sim = scene if isinstance(scene, Simulator) else Simulator(scene, **overrides)
    dt = sim.dt
    every = max(1, int(round((0.05 if record_interval is None else record_interval) / dt)))
    n_steps = int(round(duration / dt))
    rec = Recorder(sim, n_steps // every + 1)
    rec.record()
    wall0 = time.perf_counter()
    done, err, failed_at = 0, None, None
    try:
        while done < n_steps:
            k = min(every, n_steps - done)
            sim.advance_steps(k)
            done += k
            if k == every:
                rec.record()
    except SimulationDivergence as exc:
        err, failed_at = str(exc), float(exc.time)
    wall = time.perf_counter() - wall0
    res = rec.result()
    res.meta.update({"dt": dt, "wall_time_s": wall, **sim.stats})
    return RunOutcome(res, err, wall, failed_at, dict(sim.stats))


def scene_dict(name_or_scene) -> dict:
    """A plain, editable dict of a scene (embedded name, path, dict or Scene)."""
    from ..scene import load_scene
    return load_scene(name_or_scene).to_dict()


# ---------------------------------------------------------------------------------------------------
# signal processing
# ---------------------------------------------------------------------------------------------------
def harmonic(t, x, omega: float) -> complex:
    """Least-squares complex amplitude A of x(t) ~ Re(A e^{i omega t}) + c (fundamental only)."""
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    a = np.stack([np.cos(omega * t), np.sin(omega * t), np.ones_like(t)], axis=1)
    c, s, _ = np.linalg.lstsq(a, x, rcond=None)[0]
    return complex(c, -s)


def amplitude(t, x, omega: float) -> float:
    """Amplitude of the fundamental at ``omega`` (least squares)."""
    return abs(harmonic(t, x, omega))


def motion_rates(res, body: str) -> dict:
    """Surge/sway/heave rates (m/s, time derivative of the displacements about the mean tow-point path)
    and roll/pitch/yaw rates (rad/s, body axes) of a body: the quantities of thesis Table 6.1."""
    b = res.bodies[body]
    t = res.t
    out = {k: np.gradient(b[k], t) for k in ("surge", "sway", "heave")}
    out["roll"], out["pitch"], out["yaw"] = b["omega"][:, 0], b["omega"][:, 1], b["omega"][:, 2]
    return out


def rate_exceedance(rates: dict, limits: dict) -> dict:
    """Percentage of samples above each Table 6.1 limit and above at least one ("any"); rms rates.
    ``limits``: motion -> (limit, unit) with unit m/s or deg/s; angular rates are given in rad/s."""
    n = len(next(iter(rates.values())))
    anyx = np.zeros(n, bool)
    out = {}
    for k, v in rates.items():
        lim, unit = limits[k]
        vv = np.abs(np.degrees(v)) if unit == "deg/s" else np.abs(v)
        over = vv > lim
        anyx |= over
        out[k] = {"pct_over": 100.0 * float(over.mean()), "rms": float(np.sqrt(np.mean(vv ** 2))),
                  "limit": lim, "unit": unit}
    out["any"] = {"pct_over": 100.0 * float(anyx.mean())}
    return out


# ---------------------------------------------------------------------------------------------------
# formatting
# ---------------------------------------------------------------------------------------------------
def fmt(x, nd: int = 3) -> str:
    """Compact number formatting for tables (significant digits, no exponent for usual magnitudes)."""
    if x is None:
        return "—"
    if isinstance(x, str):
        return x
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "no"
    x = float(x)
    if not math.isfinite(x):
        return "—"
    if abs(x) < 5e-7:
        return "0"
    ax = abs(x)
    if ax >= 10 ** nd or ax < 10 ** -(nd + 1):
        if ax >= 1e5 or ax < 1e-4:
            return f"{x:.{max(nd - 1, 1)}e}"
        return f"{x:.0f}"
    digits = max(nd - 1 - int(math.floor(math.log10(ax))), 0)
    return f"{x:.{digits}f}"


def pct(x, nd: int = 1) -> str:
    if x is None or not math.isfinite(float(x)):
        return "—"
    return f"{float(x):+.{nd}f} %"


@dataclass
class Table:
    title: str
    columns: list
    rows: list
    notes: str = ""

    def to_dict(self):
        return {"title": self.title, "columns": list(self.columns),
                "rows": [[fmt(c) if not isinstance(c, str) else c for c in r] for r in self.rows],
                "notes": self.notes}


@dataclass
class Figure:
    file: str
    caption: str

    def to_dict(self):
        return {"file": self.file, "caption": self.caption}


def savefig(fig, outdir: Path, name: str) -> str:
    """Save a matplotlib figure as ``outdir/name`` (PNG, 110 dpi) and return the path relative to the
    report (``validation/<name>``)."""
    import matplotlib.pyplot as plt
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    try:
        fig.tight_layout()
    except Exception:  # pragma: no cover - layout is cosmetic
        pass
    from ..atomic import atomic_write
    try:
        atomic_write(outdir / name, lambda tmp: fig.savefig(tmp, dpi=110, bbox_inches="tight"), mode=None)
    finally:
        plt.close(fig)
    return f"{outdir.name}/{name}"


class Progress:
    """Progress messages for long cases (tqdm bar when available, else plain prints)."""

    def __init__(self, total: int, desc: str, enabled: bool = True):
        self.enabled = enabled
        self.bar = None
        if enabled:
            try:
                from tqdm import tqdm
                self.bar = tqdm(total=total, desc=desc, unit="run", leave=False, dynamic_ncols=True)
            except ImportError:  # pragma: no cover
                self.bar = None
        self.desc = desc

    def step(self, msg: str = "", n: int = 1):
        if self.bar is not None:
            self.bar.set_postfix_str(msg[:40])
            self.bar.update(n)
        elif self.enabled and msg:
            print(f"  [{self.desc}] {msg}", flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()


@dataclass
class CaseContext:
    """What a case needs besides its own logic: quick or full, where figures go, a progress factory."""
    quick: bool
    outdir: Path
    progress: bool = True
    log: Callable[[str], None] = print

    def bar(self, total: int, desc: str) -> Progress:
        return Progress(total, desc, self.progress)

    def tmpdir(self) -> Path:
        import tempfile
        d = Path(tempfile.mkdtemp(prefix="towenv_validation_"))
        return d


def env_fingerprint() -> dict:
    import platform

    import numba
    import numpy
    import scipy
    from .. import __version__
    return {"towenv": __version__, "python": platform.python_version(), "numpy": numpy.__version__,
            "scipy": scipy.__version__, "numba": numba.__version__, "machine": platform.machine(),
            "cpus": os.cpu_count()}
