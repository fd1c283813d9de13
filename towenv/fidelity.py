"""Automatic fidelity selection: the cheapest model of a scene that keeps the fish statistics within a tolerance.

``select(scene, sea_state, tolerance)`` returns a :class:`Fidelity`: the time step, the segment counts per
line, 2-D (vertical plane) or 3-D, and nonlinear time domain (Houbolt) or the linearised frequency-domain
model, with the predicted relative error of the fish's heave and pitch statistics against the *fine
default* (Houbolt, Δt = 0.01 s or the scene's Δt if smaller, twice the scene's segments, 3-D) and the predicted cost relative to it.
A chosen time-domain configuration also lets the Newton iteration stop on its estimated remaining error
(``solver.newton_stop = "estimate"``, :data:`NEWTON_STOP`): up to 25 % fewer iterations at the long steps chosen
here, none at the fine default's 0.01 s, which keeps the plain rule.

Solver. The time-domain candidates are Houbolt configurations: on the speed/accuracy chart
(docs/speed-accuracy.md) Houbolt's cheapest run at ≤ 1 % and at ≤ 0.1 % error is 1.6–149× cheaper than the
generalized-α, Newmark and explicit schemes' wherever those reach that accuracy (on the slack two-part tow in
SS4 no solver, Houbolt included, comes within 1 % of the converged reference), and those schemes model neither
the compensator and winch nor wave orbital velocities — so no other solver could be the cheapest choice at
equal accuracy, and none is offered.

How the error is predicted (no time-domain run is needed for the prediction itself):

* **Time step.** The linearised model (:mod:`towenv.linear`) is solved with Houbolt's *discrete*
  operators in place of ``iω`` and ``−ω²``: for a response ``x_n = X zⁿ``, ``z = e^{iωΔt}``, the Houbolt
  acceleration and velocity of the kernel are ``A(z) X`` and ``V(z) X`` with
  ``A = (2 − 5z⁻¹ + 4z⁻² − z⁻³)/Δt²`` and ``V = (11 − 18z⁻¹ + 9z⁻² − 2z⁻³)/(6Δt)``. The resulting discrete
  RAOs are exactly what the time-stepping does to the linearised system (numerical damping and period
  error at every frequency of the sea), so the change of the significant amplitudes with Δt is predicted
  rather than guessed.
* **Segments.** The same linear model built with the candidate segment counts against the fine default's.
* **2-D.** Chosen when nothing excites the lateral plane (head or following long-crested sea, no lateral
  current, no sway/yaw/roll excitation, symmetric bodies) *and* no lateral mode is unstable (the linearised
  model's damped eigenvalues, :meth:`~towenv.linear.LinearModel.damped_modes`: a growing roll/yaw mode of the
  towfish grows from round-off in 3-D, which a 2-D model cannot show); its error is then round-off (tested).
* **Linearised model.** Offered only when the tolerance is at least its measured accuracy against the
  nonlinear simulation (:data:`LINEAR_ERROR_BOUND`, docs/linear.md) and the predicted tensions stay well
  away from slack (mean tension ≥ :data:`SLACK_MARGIN` standard deviations at the top and at the fish).

The time-step and segment errors are added (conservative). Without a pilot run (below) they are multiplied
by :data:`SAFETY` (:data:`SAFETY_SLACK` where cables go slack), calibrated on the *build* cases of
``scripts/fidelity_check.py``; with one, the prediction only *screens* the candidates (× :data:`SCREEN_SAFETY`
= 1) and the pilot's measurement decides. Both are checked on held-out scenes (docs/fidelity.md).

**Pilot run.** The linear prediction cannot see failures of the nonlinear iteration (a slack cable
snapping, a body tumbling, a coupling that needs step cuts), nor what it does not model (a manoeuvre that
turns the ship into the sea, snap loads, strong drag nonlinearity). The cheapest candidates predicted within
tolerance are therefore run from the scene's start through a window of :data:`PILOT_SECONDS` after the
excitation ramp and any manoeuvre (:func:`pilot_window`; deterministic, same sea seed), and so is the fine
default once; the first candidate that completes without a single step cut *and* whose output standard deviations over the
window differ from the fine default's by no more than the tolerance divided by :data:`PILOT_SAFETY`
(a paired comparison: same forcing, so the difference is the discretisation's, not sampling noise; the factor
covers the window's roughness as an estimate of a long run's — calibrated on 126 selections of tuned cases,
``scripts/fidelity_calibration.py``) is chosen. Candidates with a Δt at or above one that failed to
run are skipped; after :data:`MAX_PILOTS` pilots the fine default is returned. Where the fish has little mean
flow (< :data:`FLOW_MARGIN` standard deviations of its velocity) the linear prediction is not trusted: the
pilot decides, with the larger safety factor :data:`SAFETY_SLACK` (also on the screen) and no fewer segments than the scene's. This replaced a fixed
Δt ≤ 0.02 s cap for series tows, whose body–tail coupling now converges at long steps (docs/model-notes.md
"Series coupling"). A selection takes 0.3–9 s with its pilots (the fine default's pilot
dominates).
"""
from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

FINE_DT = 0.01
FINE_SEGMENT_FACTOR = 2.0
#: time steps tried (s): spaced by ≤ 1.33× below 0.15 s, where head and bow seas put the choice at tight
#: tolerances (a coarser grid left up to half of the tolerance unused: 0.03 → 0.05 s is a 1.67× step)
DT_CANDIDATES = (0.01, 0.0125, 0.015, 0.0175, 0.02, 0.025, 0.03, 0.035, 0.04, 0.045, 0.05, 0.06, 0.075, 0.09,
                 0.1, 0.125, 0.15, 0.2, 0.25, 0.3)
SEGMENT_FACTORS = (0.25, 0.5, 0.75, 1.0, 1.5, 2.0)
OUTPUTS = ("fish_heave", "fish_pitch")
#: multiplies the predicted discretisation error when no pilot run checks the choice (``pilot=False``;
#: calibrated on the build cases, docs/fidelity.md)
SAFETY = 1.5
#: with pilot runs, the linear prediction only screens the candidates (prediction × SCREEN_SAFETY ≤ tolerance)
#: and the pilot's measured difference decides (× PILOT_SAFETY ≤ tolerance). Calibrated in round 8 on 126
#: selections of 42 tuned cases (``scripts/fidelity_calibration.py``, 1260 runs, docs/fidelity.md): the raw
#: prediction matches the measured error in the median but scatters (measured / predicted: median 0.98, 90th
#: percentile 2.9), the 80 s pilot window less (measured / pilot: median 1.0, 90th percentile 2.1 where cables
#: go slack, 1.5 where not); screen 1.0 with pilot factor 1.5 met the tolerance in 98 % of the selections
#: (offline replay of the calibration runs), as did the round-7 rules (SAFETY_SLACK = 2.5 on both where cables
#: go slack, as in 37 of the 42 cases), which needed ~20 % more run time
SCREEN_SAFETY = 1.0
PILOT_SAFETY = 1.5
#: measured accuracy of the linearised model's significant amplitudes in moderate seas (docs/linear.md)
LINEAR_ERROR_BOUND = 0.15
#: mean tension / tension standard deviation needed before the linearised model is offered
SLACK_MARGIN = 4.0
#: below this mean/std tension ratio (at the top or the fish segment) cables go slack in the run: the
#: linear predictor then underestimates the discretisation error (snap loads are nonlinear), so the
#: segment count is not reduced below the scene's and, without a pilot run, the safety factor is SAFETY_SLACK
#: (with one, the pilot's PILOT_SAFETY: the calibration's slack cases are where its 98 % was measured)
SLACK_NONLINEAR = 2.0
SAFETY_SLACK = 2.5
#: the fish's mean relative flow must exceed this many standard deviations of its velocity for the
#: linearised error prediction to be trusted (at U ≈ 0 the body's incidence flips through ±90° every cycle
#: and its pitch is not a linear function of the motion — docs/linear.md "where it fails"). Below it the
#: pilot run decides: a candidate needs a passed pilot (with the SAFETY_SLACK factor, also as its screen), segments are not
#: reduced below the scene's, and without a pilot the fine default is returned
FLOW_MARGIN = 2.0
#: growth rate (1/s) above which a lateral mode of the linearised model counts as unstable; such a mode grows
#: from round-off in the 3-D simulator (at the predicted rate, tests/unit/test_linear.py) and 2-D is refused. At
#: 1e-3/s it would need ~10 h of simulated time to grow from round-off to a visible amplitude
LATERAL_GROWTH_LIMIT = 1e-3
#: simulated seconds of the statistics window of the pilot run that checks a chosen configuration
#: (:func:`pilot_window`, :func:`pilot_run`)
PILOT_SECONDS = 80.0
#: at most this many candidates are piloted before falling back to the fine default
MAX_PILOTS = 8
#: ``solver.newton_stop`` of every chosen configuration: "estimate" lets the Newton iteration stop, from its
#: second iteration, when the error left in the iterate (estimated from the observed contraction) is within the
#: solver tolerances. At the long steps chosen here it saves 10–25 % of the iterations in head and bow seas
#: (1–6 % in a following sea or a series tow) and moved the fish statistics by ≤ 0.35 % in 15 measured choices;
#: at the fine default's 0.01 s it changes nothing (tests/unit/test_newton_stop.py), so the fine default keeps the
#: plain rule. Not the simulator's default: at very long steps (≥ 0.5 s) it was less
#: robust (docs/model-notes.md); the choices here are ≤ 0.3 s and each passes a pilot run
NEWTON_STOP = "estimate"


def fine_time_step(scene) -> float:
    """Δt of the fine default: :data:`FINE_DT`, or the scene's own ``solver.dt`` if that is smaller
    (model-scale scenes, e.g. the channel runs, are written with millisecond steps)."""
    return min(FINE_DT, float(scene.solver.dt))


def fine_default(scene, outputs=(), tolerance: float = 0.0) -> "Fidelity":
    """The fine default every error is measured against: Houbolt at :func:`fine_time_step`, FINE_SEGMENT_FACTOR
    × the scene's segments, 3-D (its predicted error is 0 for ``outputs``)."""
    from .core.simulator import load
    sc = load(scene)
    return Fidelity("houbolt", fine_time_step(sc), FINE_SEGMENT_FACTOR, scaled_segments(sc, FINE_SEGMENT_FACTOR),
                    False, {k: 0.0 for k in outputs}, 1.0, float(tolerance))


def houbolt_operators(omega, dt):
    """Houbolt's discrete acceleration and velocity operators ``A(ω), V(ω)`` (replace ``−ω²`` and ``iω``)."""
    z1 = np.exp(-1j * np.asarray(omega, float) * dt)
    a = (2.0 - 5.0 * z1 + 4.0 * z1 ** 2 - z1 ** 3) / (dt * dt)
    v = (11.0 - 18.0 * z1 + 9.0 * z1 ** 2 - 2.0 * z1 ** 3) / (6.0 * dt)
    return a, v


@dataclass
class Fidelity:
    """A chosen model configuration (see :func:`select`)."""
    method: str                     # "houbolt" (nonlinear time domain) or "linear" (frequency domain)
    dt: float | None
    segment_factor: float
    segments: dict                  # line name -> int or tuple per span
    planar: bool
    predicted_error: dict           # output -> predicted relative error of its significant amplitude
    relative_cost: float            # predicted wall time / the fine default's
    tolerance: float
    reason: str = ""
    candidates: list = field(default_factory=list, repr=False)
    seconds: float = 0.0
    pilot: str = ""                 # outcome of the pilot run(s) (empty when none was made)
    pilot_error: float | None = None  # measured error of the statistics over the pilot window
    newton_stop: str = "change"     # solver.newton_stop of the configuration (NEWTON_STOP for the choices)
    prediction_factor: float = 1.0  # the factor select() applied to the raw linear prediction of the candidates

    @property
    def error(self) -> float:
        return max(self.predicted_error.values()) if self.predicted_error else 0.0

    def overrides(self) -> dict:
        """Scene overrides (dotted paths) that realise this configuration in the time-domain simulator."""
        out = {}
        if self.dt is not None:
            out["solver.dt"] = float(self.dt)
        for name, n in self.segments.items():
            out[f"lines.{name}.segments"] = list(n) if isinstance(n, tuple) else int(n)
        if self.planar:
            out["solver.planar"] = True
        if self.method == "houbolt" and self.newton_stop != "change":
            out["solver.newton_stop"] = self.newton_stop
        return out

    def apply(self, scene):
        from .core.simulator import load
        return load(scene).with_overrides(self.overrides())

    def summary(self) -> str:
        seg = ", ".join(f"{k} {v}" for k, v in self.segments.items())
        if self.method == "linear":
            head = "linearised frequency-domain model"
        else:
            head = f"Houbolt Δt = {self.dt:g} s, {'2-D' if self.planar else '3-D'}"
            if self.newton_stop == "estimate":
                head += ", Newton stop on the estimated error"
        errs = ", ".join(f"{k} {100 * v:.2g} %" for k, v in self.predicted_error.items())
        return (f"{head}; segments: {seg}; predicted error {errs} (tolerance {100 * self.tolerance:g} %); "
                f"cost {self.relative_cost:.3g} × the fine default")


# ------------------------------------------------------------------------------------------------------
def scaled_segments(scene, factor: float) -> dict:
    """Segment counts per line scaled by ``factor`` (at least one per span), as scene values."""
    out = {}
    for ln in scene.lines:
        spans = ln.span_segments(scene.junctions(ln.name)) if hasattr(scene, "junctions") else [ln.segments]
        new = tuple(max(1, int(round(factor * n))) for n in spans)
        out[ln.name] = new if isinstance(ln.segments, tuple) else int(sum(new)) if len(new) == 1 else new
    return out


def _with_segments(scene, segs):
    return scene.with_overrides({f"lines.{k}.segments": (list(v) if isinstance(v, tuple) else v)
                                 for k, v in segs.items()})


def _n_nodes(segs) -> int:
    return int(sum(sum(v) if isinstance(v, tuple) else v for v in segs.values()))


def lateral_excitation(scene, sea_state) -> str | None:
    """Why the scene is not planar (a string), or None when nothing excites the lateral plane."""
    cur = getattr(scene, "current", None)
    if cur is not None:
        prof = getattr(cur, "profile", None) or []
        for p in prof:
            v = p[1:] if len(p) > 2 else p
            if len(v) >= 2 and abs(float(v[1])) > 0:
                return "current has a lateral (y) component"
        vel = getattr(cur, "velocity", None)
        if vel is not None and len(vel) > 1 and abs(float(vel[1])) > 0:
            return "current has a lateral (y) component"
    ves = scene.vessel
    for e in getattr(ves, "excitation", None) or []:
        ax = getattr(e, "axis", "z")
        if ax not in ("x", "z", "pitch"):
            return f"vessel excitation on axis {ax!r}"
    if getattr(ves, "manoeuvres", None) or getattr(ves, "turn", None):
        return "the vessel manoeuvres"
    if sea_state is not None:
        h = float(sea_state.heading_deg) % 360.0
        if min(abs(h - 0.0), abs(h - 180.0), abs(h - 360.0)) > 1e-9:
            return f"sea heading {sea_state.heading_deg:g}° is not head or following"
        if sea_state.spreading_s is not None:
            return "short-crested sea (spreading)"
    return None


def _sea_of(scene, sea_state):
    if sea_state is not None:
        return sea_state
    sea = getattr(scene, "sea", None)
    return sea.sea_state() if sea is not None else None


class _Predictor:
    """Linear-model statistics of the fish outputs for a segment factor and a time step (cached)."""

    def __init__(self, scene, sea_state, outputs):
        from .linear import LinearModel
        self.scene, self.sea, self.outputs = scene, sea_state, outputs
        self._lm = {}
        self._LM = LinearModel

    def model(self, factor):
        if factor not in self._lm:
            sc = _with_segments(self.scene, scaled_segments(self.scene, factor))
            self._lm[factor] = self._LM(sc)
        return self._lm[factor]

    def stats(self, factor, dt):
        """Standard deviations of the outputs (continuous time when ``dt`` is None)."""
        lm = self.model(factor)
        if self.sea is None:
            return self._sinusoid_stats(lm, dt)
        with _houbolt_time(lm, dt):
            r = lm.spectral(self.sea)
        return {k: r.std[k] for k in self.outputs if k in r.std}, r

    def flow_margin(self, factor) -> float:
        """|mean relative flow at the fish| / std of the fish's velocity (surge + heave), continuous time."""
        from .core import kernels as K
        lm = self.model(factor)
        s = lm.system
        node = lm.fish.node if lm.fish is not None else int(s.lines[0].nodes[-1])
        cur = np.zeros(3)
        K.current_at(float(lm.r0[node, 2]), s.cur_z, s.cur_v, cur)
        u_rel = float(np.linalg.norm(np.asarray(lm.U, float) - cur))
        saved = self.outputs
        self.outputs = ("fish_surge", "fish_heave")
        try:
            if self.sea is None:
                var = 0.0
                for period, top in self._sinusoids().items():
                    w = 2 * math.pi / period
                    r = lm.response(np.array([w]), top=top)
                    amp = float(np.linalg.norm(top))
                    var += sum(0.5 * (abs(r.rao[k][0]) * amp * w) ** 2 for k in self.outputs)
            else:
                r = lm.spectral(self.sea)
                dw = np.gradient(r.omega)
                var = float(sum(np.sum(np.abs(r.raos[k]) ** 2 * r.omega_e ** 2 * r.wave_spectrum * dw)
                                for k in self.outputs))
        finally:
            self.outputs = saved
        sd = math.sqrt(var)
        return u_rel / sd if sd > 0 else np.inf

    def unstable_lateral_mode(self, factor):
        """(growth rate σ (1/s), period (s)) of the fastest-growing mode that lives mainly in the lateral plane
        (:meth:`towenv.linear.LinearModel.damped_modes`), or None when none grows faster than
        :data:`LATERAL_GROWTH_LIMIT`."""
        lam, frac = self.model(factor).damped_modes()
        for l, f in zip(lam, frac):
            if l.real <= LATERAL_GROWTH_LIMIT:
                return None
            if f >= 0.5:
                return float(l.real), (2 * math.pi / abs(l.imag) if l.imag != 0 else math.inf)
        return None

    def _sinusoids(self):
        comps = [e for e in (self.scene.vessel.excitation or []) if getattr(e, "type", "") == "sinusoid"]
        if not comps:
            raise ValueError("fidelity.select: the scene has no sea and no sinusoidal excitation; give sea_state")
        by_period = {}
        for e in comps:
            if e.axis not in ("x", "y", "z"):
                raise ValueError(f"fidelity.select: sinusoidal excitation on axis {e.axis!r} is not supported by the "
                                 "linearised predictor (x, y, z only); give sea_state")
            top = by_period.setdefault(float(e.period), np.zeros(3, complex))
            top["xyz".index(e.axis)] += float(e.amplitude) * np.exp(1j * math.radians(float(getattr(e, "phase_deg", 0.0))))
        return by_period

    def slack_margin(self, factor) -> float:
        """min(mean / std) of the tension of the top segment and of the fish's segment (continuous time)."""
        lm = self.model(factor)
        keys = ("top_segment_tension", "fish_tension")
        saved = self.outputs
        self.outputs = keys
        try:
            sd, _ = self.stats(factor, None)
        finally:
            self.outputs = saved
        s = lm.system
        top_seg = int(s.node_segs[int(s.cable_top_node), 0])
        fish_node = lm.fish.node if lm.fish is not None else int(s.lines[0].nodes[-1])
        fish_seg = int(s.node_up_seg[fish_node]) if lm.fish is not None else int(s.lines[0].segments[-1])
        out = np.inf
        for key, seg in (("top_segment_tension", top_seg), ("fish_tension", fish_seg)):
            if sd[key] > 0:
                out = min(out, float(lm.T0[seg]) / sd[key])
        return float(out)

    def _sinusoid_stats(self, lm, dt):
        # the scene's own sinusoidal tow-point excitation: std = sqrt(Σ |X_k|² / 2)
        var = {k: 0.0 for k in self.outputs}
        present = set(var)
        last = None
        by_period = self._sinusoids()
        for period, top in by_period.items():
            w = np.array([2 * math.pi / period])
            with _houbolt_time(lm, dt):
                r = lm.response(w, top=top)
            amp = float(np.linalg.norm(top))
            for k in self.outputs:
                if k in r.rao:
                    var[k] += 0.5 * (abs(r.rao[k][0]) * amp) ** 2
                else:
                    var.pop(k, None)
            last = r
        return {k: math.sqrt(v) for k, v in var.items() if k in present}, last


@contextmanager
def _houbolt_time(lm, dt):
    """Within the block, ``lm`` solves the Houbolt-discretised system at step ``dt`` (continuous if None)."""
    if dt is None:
        yield
        return
    lm._solve = lambda omega, *a: _discrete_solve(omega, dt, *a)
    try:
        yield
    finally:
        del lm._solve


def _discrete_solve(omega, dt, Utop, Kq, Ku, Mq, Mu, C, Cu, Cadd):
    """``LinearModel._solve`` with Houbolt's discrete operators in place of ``−ω²`` and ``iω``."""
    a, v = houbolt_operators(omega, dt)
    a = a[:, None, None]
    v = v[:, None, None]
    A = Kq[None] + a * Mq[None] + v * (C + Cadd[None])
    B = Ku[None] + a * Mu[None] + v * Cu
    rhs = -np.einsum("fij,fj->fi", B, Utop)
    X = np.linalg.solve(A, rhs[..., None])[..., 0]
    if not np.all(np.isfinite(X)):
        raise FloatingPointError("non-finite discrete response")
    return np.ascontiguousarray(X)


def _ratio_dev(a, b):
    return a / b - 1.0 if b > 0 else 0.0


def select(scene, sea_state=None, tolerance: float = 0.05, *, outputs=OUTPUTS, allow_linear: bool = True,
           allow_planar: bool = True, dt_candidates=DT_CANDIDATES, segment_factors=SEGMENT_FACTORS,
           safety: float = SAFETY, fixed_segments: bool = False, pilot: bool = True,
           pilot_seconds: float = PILOT_SECONDS, screen_safety: float = SCREEN_SAFETY,
           pilot_safety: float = PILOT_SAFETY) -> Fidelity:
    """The cheapest configuration predicted to keep the significant amplitudes of ``outputs`` (fish heave
    and pitch by default) within ``tolerance`` (relative, e.g. 0.05) of the fine default.

    ``sea_state``: a :class:`towenv.sea.SeaState`; default the scene's ``[sea]``, else the scene's
    sinusoidal tow-point excitation. Errors are predicted with the linearised model (module docstring):
    ``e = s · (|δ_seg(f)| + |δ_Δt(Δt) − δ_Δt(Δt_fine)|)`` with ``δ_seg`` the relative change of the
    statistic with the segment factor ``f`` (vs ×2) and ``δ_Δt`` its relative change from continuous time
    to Houbolt at Δt (scene segments); ``s`` is ``screen_safety`` (:data:`SCREEN_SAFETY`) when pilot runs
    check the choice — the prediction then only screens the candidates and the pilot's measured difference
    × ``pilot_safety`` (:data:`PILOT_SAFETY`) must be within the tolerance — and ``safety`` (:data:`SAFETY`,
    :data:`SAFETY_SLACK` where cables go slack) without them. Where the fish has little mean flow both
    factors are raised to :data:`SAFETY_SLACK`. Cost = :func:`step_cost` relative to the fine default (× the measured
    2-D saving when planar). ``fixed_segments=True`` keeps the scene's segment counts and chooses Δt alone
    (its error then counts the time step only). ``pilot=True``: the cheapest candidates are run for
    ``pilot_seconds`` from the scene's start, and the first that completes without a step cut is taken
    (:func:`pilot_run`; ``Fidelity.pilot`` says what happened) — the linear prediction cannot see Newton
    failures (slack snaps, a tumbling body)."""
    from .core.simulator import load
    t0 = time.perf_counter()
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float)) or not (0.0 < tolerance < 1.0):
        raise ValueError(f"tolerance: must be a relative error in (0, 1), e.g. 0.05, got {tolerance!r}")
    unknown = [k for k in outputs if k not in ("fish_heave", "fish_pitch", "fish_surge", "fish_sway", "fish_roll",
                                               "fish_yaw", "top_tension", "fish_tension")]
    if unknown or not outputs:
        raise ValueError(f"outputs: must be a non-empty subset of fish_heave, fish_pitch, fish_surge, fish_sway, "
                         f"fish_roll, fish_yaw, top_tension, fish_tension; got {outputs!r}")
    for name, val in (("safety", safety), ("screen_safety", screen_safety), ("pilot_safety", pilot_safety)):
        if isinstance(val, bool) or not isinstance(val, (int, float)) or not (0.0 < val <= 100.0):
            raise ValueError(f"{name}: must be a factor in (0, 100] multiplying an error estimate, got {val!r}")
    if isinstance(pilot_seconds, bool) or not isinstance(pilot_seconds, (int, float)) or \
            not (5.0 <= pilot_seconds <= 3600.0):
        raise ValueError(f"pilot_seconds: must be a window length in [5, 3600] s, got {pilot_seconds!r}")
    for name, vals, lo, hi in (("dt_candidates", dt_candidates, 1e-4, 1.0),
                               ("segment_factors", segment_factors, 0.05, 8.0)):
        v = np.asarray(vals, float)
        if v.ndim != 1 or len(v) == 0 or not np.all((v >= lo) & (v <= hi)):
            raise ValueError(f"{name}: must be a non-empty list of values in [{lo:g}, {hi:g}], got {vals!r}")
    sc = load(scene)
    sea = _sea_of(sc, sea_state)
    pred = _Predictor(sc, sea, tuple(outputs))
    cont_ref, ref_res = pred.stats(FINE_SEGMENT_FACTOR, None)
    cont_1, _ = pred.stats(1.0, None)
    if not cont_ref:
        raise ValueError(f"outputs: none of {tuple(outputs)} exists for this scene (no fish body?)")
    big = max(cont_ref.values())
    used = [k for k in outputs if k in cont_ref and cont_ref[k] > 1e-9 * max(big, 1e-300)]
    margin = pred.slack_margin(FINE_SEGMENT_FACTOR)
    slack = margin < SLACK_NONLINEAR
    flow = pred.flow_margin(FINE_SEGMENT_FACTOR)
    low_flow = flow < FLOW_MARGIN
    if slack or low_flow:
        safety = max(safety, SAFETY_SLACK)
        segment_factors = [f for f in segment_factors if f >= 1.0] or [1.0]
    if low_flow:        # the linear prediction is not trusted: the larger factor screens and judges the pilot
        screen_safety = max(screen_safety, SAFETY_SLACK)
        pilot_safety = max(pilot_safety, SAFETY_SLACK)
    factor = screen_safety if pilot else safety
    if fixed_segments:
        segment_factors = [1.0]
    d_seg = {}
    for f in segment_factors:
        s, _ = pred.stats(float(f), None) if f != 1.0 else (cont_1, None)
        d_seg[float(f)] = {k: _ratio_dev(s[k], cont_ref[k]) for k in used}
    d_dt = {}
    fine_dt = fine_time_step(sc)
    if dt_candidates is DT_CANDIDATES and fine_dt < min(DT_CANDIDATES):
        # model-scale scenes: also try small multiples of the scene's own step
        dt_candidates = tuple(sorted(set(DT_CANDIDATES) | {fine_dt * m for m in (1, 2, 3, 5)}))
    for dt in sorted(set(float(x) for x in dt_candidates) | {fine_dt}):
        s, _ = pred.stats(1.0, dt)
        d_dt[dt] = {k: _ratio_dev(s[k], cont_1[k]) for k in used}
    why_not_planar = lateral_excitation(sc, sea) if allow_planar else "2-D not allowed by the caller"
    if why_not_planar is None:
        why_not_planar = _planar_refusal(sc)
    lateral = pred.unstable_lateral_mode(FINE_SEGMENT_FACTOR)
    if lateral is not None and why_not_planar is None and allow_planar:
        why_not_planar = (f"the linearised model has an unstable lateral mode (growth rate {lateral[0]:.2g}/s, "
                          f"period {lateral[1]:.3g} s) that a 2-D model cannot have")
    planar = why_not_planar is None
    fine_segs = scaled_segments(sc, FINE_SEGMENT_FACTOR)
    irregular = sea is not None
    n_bodies = sum(1 for b in sc.bodies if getattr(b, "kind", "") in ("fish", "depressor"))
    fine_cost = step_cost(_n_nodes(fine_segs), fine_dt, irregular, n_bodies)
    cands = []
    for f in segment_factors:
        segs = scaled_segments(sc, float(f))
        for dt in dt_candidates:
            dt = float(dt)
            seg_part = 0.0 if fixed_segments else 1.0
            err = {k: factor * (seg_part * abs(d_seg[float(f)][k]) + abs(d_dt[dt][k] - d_dt[fine_dt][k]))
                   for k in used}
            cost = step_cost(_n_nodes(segs), dt, irregular, n_bodies) / fine_cost * (PLANAR_COST if planar else 1.0)
            cands.append(Fidelity("houbolt", dt, float(f), segs, planar, err, cost, float(tolerance),
                                  seconds=0.0, newton_stop=NEWTON_STOP, prediction_factor=float(factor)))
    ok = [c for c in cands if c.error <= tolerance]
    reason = ""
    if low_flow:
        reason = (f"the fish's mean relative flow is only {flow:.2g} × its velocity std (< {FLOW_MARGIN:g}): its "
                  "hydrodynamics are strongly nonlinear and the linear error prediction is not trusted")
        if not pilot:
            ok = []
            reason += " (and no pilot run was allowed) — "
        else:
            reason += f": the pilot decides, safety factor {pilot_safety:g}, segments not reduced — "
    pilot_notes = []
    if ok and pilot:
        fine_ov = fine_default(sc).overrides()
        ok = _piloted(sc, sorted(ok, key=lambda c: (c.relative_cost, c.error)), pilot_seconds, pilot_notes,
                      tuple(used), float(tolerance), fine_ov, pilot_safety)
    if ok:
        best = min(ok, key=lambda c: (c.relative_cost, c.error))
        reason += f"cheapest of {len(ok)}/{len(cands)} Houbolt configurations predicted within tolerance"
        if pilot:
            reason += " that passed the pilot run"
    elif fixed_segments:
        segs = scaled_segments(sc, 1.0)
        best = Fidelity("houbolt", fine_dt, 1.0, segs, False, {k: 0.0 for k in used},
                        step_cost(_n_nodes(segs), fine_dt, irregular, n_bodies) / fine_cost, float(tolerance))
    else:
        best = fine_default(sc, used, tolerance)
        if pilot_notes:
            reason += "no cheaper configuration passed its pilot run: the fine default"
        elif low_flow and not pilot:
            reason += "the fine default"
        else:
            reason += "no cheaper configuration is predicted within tolerance: the fine default"
    if planar and best.planar:
        reason += "; 2-D (nothing excites the lateral plane)"
    elif allow_planar:
        reason += f"; 3-D ({why_not_planar})" if why_not_planar else "; 3-D"
    if lateral is not None:
        reason += (f"; warning: an unstable lateral mode (growth rate {lateral[0]:.2g}/s) makes long-run "
                   "statistics depend on when it reaches large amplitude (in any model that has it)")
    if slack:
        reason += (f"; cables go slack (mean tension only {margin:.2g} std above zero): segments not reduced"
                   + (f", pilot safety factor {pilot_safety:g}" if pilot else f", safety factor {safety:g}"))
    if allow_linear and tolerance >= LINEAR_ERROR_BOUND and flow >= FLOW_MARGIN:
        if margin >= SLACK_MARGIN:
            best = Fidelity("linear", None, FINE_SEGMENT_FACTOR, fine_segs, False,
                            {k: LINEAR_ERROR_BOUND for k in used}, 0.0, float(tolerance))
            reason = (f"linearised model: tolerance ≥ its measured accuracy ({100 * LINEAR_ERROR_BOUND:g} %) and "
                      f"mean tension ≥ {margin:.1f} std (no slack)")
        else:
            reason += f"; linearised model rejected: mean tension only {margin:.1f} std above zero (slack risk)"
    best.reason = reason
    best.prediction_factor = float(factor)
    best.candidates = cands
    best.pilot = "; ".join(pilot_notes)
    best.seconds = time.perf_counter() - t0
    return best


def pilot_window(scene, seconds: float = PILOT_SECONDS) -> tuple[float, float]:
    """(start, end) of the pilot's statistics window: 10 s after the excitation ramp and the last manoeuvre
    have ended (the run's later statistics are those of the steady state), ``seconds`` long."""
    ves = getattr(scene, "vessel", None)
    ramp = getattr(ves, "ramp", None)
    t0 = float(ramp.duration) if ramp is not None and ramp.type != "none" else 0.0
    for w in (ves.schedule() if ves is not None and hasattr(ves, "schedule") else []):
        if math.isfinite(w.end_time):
            t0 = max(t0, float(w.end_time))
    t0 += 10.0
    return t0, t0 + float(seconds)


def _fish_of(scene) -> str | None:
    fish = [b.name for b in scene.bodies if getattr(b, "kind", "") == "fish"]
    return fish[0] if fish else (scene.bodies[-1].name if scene.bodies else None)


_PILOT_SERIES = {"fish_heave": lambda r, f: r.bodies[f]["heave"], "fish_pitch": lambda r, f: r.bodies[f]["euler"][:, 1],
                 "fish_surge": lambda r, f: r.bodies[f]["surge"], "fish_sway": lambda r, f: r.bodies[f]["sway"],
                 "fish_roll": lambda r, f: r.bodies[f]["euler"][:, 0], "fish_yaw": lambda r, f: r.bodies[f]["euler"][:, 2],
                 "top_tension": lambda r, f: r.top_tension}


def pilot_run(scene, overrides: dict, seconds: float = PILOT_SECONDS, outputs=OUTPUTS):
    """Run ``scene`` with ``overrides`` from its start through :func:`pilot_window` (same sea seed,
    deterministic). Returns ``(passed, note, stats)``: ``passed`` when the run completes without a step
    cut (a halved step means the Newton iteration did not converge at this Δt somewhere — a failure the
    linear error prediction cannot see: slack snaps, a body tumbling); ``stats`` are the standard
    deviations of ``outputs`` over the window (None when the run failed)."""
    from .core.run import simulate
    from .core.simulator import Simulator
    from .errors import SimulationDivergence
    t0, t1 = pilot_window(scene, seconds)
    try:
        sim = Simulator(scene.with_overrides(overrides))
        res = simulate(sim, t1)
    except SimulationDivergence as exc:
        return False, f"diverged at t = {exc.time:.1f} s ({exc.cause.split(' (')[0]})", None
    except (ValueError, FloatingPointError) as exc:
        return False, f"refused: {str(exc)[:120]}", None
    st = sim.stats
    fish = _fish_of(scene)
    m = res.t >= t0
    stats = {k: float(np.std(_PILOT_SERIES[k](res, fish)[m])) for k in outputs
             if k in _PILOT_SERIES and (fish is not None or k == "top_tension")}
    if st["step_cuts"]:
        return False, f"{st['step_cuts']} step cuts in {t1:g} s", stats
    return True, f"{st['mean_iterations']:.2f} Newton iterations per step, no step cuts", stats


def _pilot_error(stats, ref):
    errs = [abs(stats[k] / ref[k] - 1.0) for k in ref if k in stats and ref[k] > 0.0]
    return max(errs) if errs else 0.0


def _piloted(sc, ordered, seconds, notes, outputs, tolerance, fine_overrides, safety):
    """The candidates (cheapest first) from the first one whose pilot run passes — completes without a step
    cut, and ``safety`` × the difference of its output statistics from the fine default's over the pilot
    window (same seed: a paired comparison) is within ``tolerance`` — or [] when none of the first
    MAX_PILOTS does. ``safety`` is :data:`PILOT_SAFETY` (:data:`SAFETY_SLACK` where the fish has little mean
    flow): an 80 s window estimates the discretisation error of a long run's statistics only roughly
    (measured / pilot-window error in the calibration runs: median 1.0, 90th percentile 2.1 where cables go
    slack, 1.5 where they do not), and the factor was set on the selection's success rate (:data:`PILOT_SAFETY`).
    A candidate is skipped without a run when one with the same or a smaller Δt has already failed to
    run, or when a pilot with at least its segment factor missed the statistics by a factor ``e/target > 1``
    and the candidate's Δt is above that pilot's Δt × (target/e)^½ (the error of the statistics falls at
    least as Δt² — Houbolt's period error; its numerical damping falls as Δt³ — so such a candidate is
    expected to miss as well; ``target`` = tolerance / safety). Without this the cheapest candidates,
    tried one by one, could use up the MAX_PILOTS and return the fine default at a loose tolerance while a
    tighter one found a choice."""
    failed_dt = math.inf
    missed = []          # (Δt, segment factor, error / target) of pilots that missed the statistics
    target = tolerance / safety
    ref = None
    tried = 0
    for i, c in enumerate(ordered):
        if c.dt is not None and c.dt >= failed_dt:
            continue
        if c.dt is not None and any(c.segment_factor <= f and c.dt > dt * ratio ** -0.5 for dt, f, ratio in missed):
            continue
        if tried >= MAX_PILOTS:
            notes.append(f"no candidate passed within {MAX_PILOTS} pilots")
            break
        tried += 1
        passed, note, stats = pilot_run(sc, c.overrides(), seconds, outputs)
        tag = f"Δt = {c.dt:g} s{', 2-D' if c.planar else ''}, segment factor {c.segment_factor:g}"
        if passed:
            if ref is None:
                ok_ref, note_ref, ref = pilot_run(sc, fine_overrides, seconds, outputs)
                if ref is None:
                    notes.append(f"pilot of the fine default failed ({note_ref}): statistics not compared")
                    ref = {}
            err = _pilot_error(stats, ref)
            c.pilot_error = err
            if safety * err <= tolerance:
                notes.append(f"pilot {seconds:g} s passed ({tag}): {note}; statistics within {100 * err:.2g} % "
                             f"of the fine default's over the window (× safety {safety:g} ≤ tolerance)")
                return [c] + [d for d in ordered[i + 1:] if d.dt is None or d.dt < failed_dt]
            notes.append(f"pilot {seconds:g} s failed ({tag}): statistics {100 * err:.2g} % from the fine default's "
                         f"(× safety {safety:g} > tolerance)")
            if c.dt is not None:
                missed.append((c.dt, c.segment_factor, err / target))
            continue
        notes.append(f"pilot {seconds:g} s failed ({tag}): {note}")
        failed_dt = min(failed_dt, c.dt if c.dt is not None else math.inf)
    return []


#: wall time of the 2-D model relative to 3-D at equal settings: 1.18–1.27× faster on two_part_tow_1,
#: conventional_tow and hover_deep_tow (docs/model-notes.md "Reduced models")
PLANAR_COST = 0.8


def _planar_refusal(scene) -> str | None:
    """Why the simulator refuses ``solver.planar`` for this scene (its own checks), or None."""
    from .core.simulator import Simulator
    try:
        Simulator(scene.with_overrides({"solver.planar": True}))
    except ValueError as exc:
        return str(exc).split(" — ")[0]
    return None


def step_cost(n_segments: int, dt: float, irregular_sea: bool = False, n_bodies: int = 1) -> float:
    """Relative wall time per simulated second of a Houbolt run (µs per simulated second on the machine of
    the fit): ``(a₀ + a_sea + it(Δt)·(b_seg·segments + b_body·bodies)) / Δt`` with ``it(Δt) = 1 + 10 Δt``
    Newton iterations per step, a₀ = 1.24 µs per step outside the iteration, a_sea = 11.1 µs per step for
    the vessel motion when an irregular sea drives it, b_seg = 0.32 µs per segment and b_body = 6.2 µs per
    rigid body per iteration. Fitted by ``python scripts/fidelity_cost_fit.py`` to 105 timed 300 s runs of
    scenes that are not held out (Table 4.1 sinusoid tows, coastal-sea variants, series_multitow in SS3;
    Δt 0.01–0.2 s, segment factors 0.5–2): median error 6.7 %, largest 31 %."""
    per_step = 1.24 + (11.07 if irregular_sea else 0.0) + (1.0 + 10.0 * dt) * (0.323 * n_segments + 6.16 * n_bodies)
    return per_step / dt


#: tolerance used to choose Δt when a scene does not set ``solver.dt`` and no tolerance is given
DEFAULT_TOLERANCE = 0.05


def configure(scene, sea_state=None, tolerance: float | None = None, *, dt_candidates=DT_CANDIDATES,
              overrides=None, allow_planar: bool = True):
    """Apply :func:`select` where the user did not fix the settings; returns ``(scene, Fidelity or None)``.

    * ``tolerance`` given, or the scene sets ``solver.fidelity``: Δt, the segment counts and 2-D/3-D are
      all chosen (time domain only — the linearised model is a separate tool, :mod:`towenv.linear`);
    * otherwise, when neither the scene nor ``overrides`` set ``solver.dt``: Δt alone is chosen for
      :data:`DEFAULT_TOLERANCE`, keeping the scene's segments;
    * otherwise the scene is returned unchanged (``None``).
    ``overrides``: the dotted overrides / solver keywords the caller will apply (``dt`` or
    ``solver.dt`` there count as fixing the time step)."""
    from .core.simulator import load
    sc = load(scene)
    ov = dict(overrides or {})
    dt_fixed = "dt" in sc.solver.model_fields_set or "dt" in ov or "solver.dt" in ov
    tol = tolerance if tolerance is not None else sc.solver.fidelity
    if tol is None and dt_fixed:
        return sc, None
    if sc.solver.method != "houbolt":
        return sc, None
    full = tol is not None
    if full:       # asking for the automatic choice overrides the scene's own Δt; only the caller's fixes it
        dt_fixed = "dt" in ov or "solver.dt" in ov
    try:
        ch = select(sc, sea_state, tol if full else DEFAULT_TOLERANCE, allow_linear=False,
                    dt_candidates=dt_candidates, fixed_segments=not full, allow_planar=allow_planar and full)
    except (ValueError, FloatingPointError) as exc:   # LinearisationError is a ValueError
        if full:
            raise ValueError(f"solver.fidelity: automatic fidelity selection is not possible for scene "
                             f"{sc.name!r}: {exc}") from None
        return sc, None          # nothing to predict from (e.g. no excitation): the schema's default dt
    o = ch.overrides()
    if dt_fixed:
        o.pop("solver.dt", None)
    if "newton_stop" in sc.solver.model_fields_set or "newton_stop" in ov or "solver.newton_stop" in ov:
        o.pop("solver.newton_stop", None)      # the user's own choice stands
    return sc.with_overrides(o), ch
