"""Clairvoyant references: the best the actuator can do with perfect knowledge of the episode's future.

A reference that a causal controller beats is not a reference. These controllers see the whole future of the
episode — the same sea state, wave seed and therefore the same tow-point motion the evaluation will run — and
*plan* the actuator's trajectory within the **same** limits, on the simulator itself:

* ``clairvoyant`` (WinchPayout): the winch-line length trajectory L(t) (payout speed and acceleration limits,
  travel) that minimises the variance of the fish heave over the scored window;
* ``clairvoyant_active`` (CompensatorGains): the sheave's stroke trajectory s(t) within the same stroke (±half
  stroke, the compensator in ``position`` mode with a fast actuator) that minimises the same variance. Any
  semi-active (k, b) law only produces stroke trajectories inside that set, so this is an **upper bound** on
  what any semi-active law — RL included — can reach with this stroke (a relaxation: it may not be attainable).

Method (iterative learning control on the episode, "optimised payout trajectory using the simulator itself"):

1. Identify the fish-heave response to the input p (length change or stroke) in nearly calm water as a finite
   impulse response h (``fir_seconds`` long) by least squares on a random, limit-respecting excitation.
2. Start from the feed-forward plan: track the future along-cable displacement of the tow point (winch) or the
   negative tow-point heave (stroke) as closely as the limits allow (a QP).
3. Simulate the plan on the nonlinear simulator (the episode's own sea and seed), take the measured fish heave
   y_j, and solve  min ‖P_W (y_j + H (p − p_j))‖² + ρ‖p − p_j‖²  subject to the limits
   (P_W removes the mean over the scored window W, H = the FIR's Toeplitz matrix); step towards the solution
   with a line search on the simulator (full, half, quarter step) and keep the plan whose *simulated*
   σ(heave) is lowest; without progress, tighten the trust region ρ. Repeat ``iterations`` times.

The plan is then replayed open loop: the evaluation runs exactly the simulated episode (same seeds, deterministic
simulator), so its score is the planner's own measured score. The optimisations are L-BFGS-B on the input's second differences (box = acceleration limit, speed and
travel as penalties), with the FIR applied by FFT.
"""
from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass

import numpy as np

from .baselines import Baseline
from .common import sea_key

__all__ = ["ClairvoyantWinch", "ClairvoyantActiveCompensator", "identify_fir", "PlanResult", "plan_episode"]


# ============================================================================ simulation of a plan
def _episode(env, sea, seed, commands, apply):
    """Run one episode of ``env`` (unwrapped TowEnv) in (sea, seed) applying ``apply(env, k, commands)`` before
    step k; returns dict of arrays per control step: fish heave, winch length dev / stroke, along displacement."""
    u = env
    u.reset(seed=int(seed), options={"sea_state": sea, "sea_seed": int(seed)})
    n = u.max_steps
    y = np.empty(n)
    d_al = np.empty(n)
    tz = np.empty(n)
    p = np.empty(n)
    slack = np.empty(n, bool)
    ok = True
    for k in range(n):
        a = np.asarray(apply(u, k, commands), np.float32)      # as a policy's predict() hands it over
        _, _, term, trunc, info = u.step(a)
        m = u._last_m
        y[k] = info["fish_heave"]
        d_al[k] = m["tow_disp_along"]
        tz[k] = m["tow_heave"]
        p[k] = m["winch_length_dev"] if "winch_length_dev" in m else m["comp_stroke"] * u.half_stroke
        slack[k] = info["slack"]
        if term or (trunc and k < n - 1):
            ok = False
            y[k + 1:] = y[k]
            d_al[k + 1:] = d_al[k]
            tz[k + 1:] = tz[k]
            p[k + 1:] = p[k]
            slack[k + 1:] = slack[k]
            break
    return {"heave": y, "disp_along": d_al, "tow_heave": tz, "input": p, "slack": slack, "ok": ok}


def _apply_winch(env, k, L):
    """Winch: command the payout speed that moves the length from plan[k-1] to plan[k] in one control step."""
    prev = L[k - 1] if k > 0 else 0.0
    v = (L[k] - prev) / env.dt
    return np.array([v / env.winch_max_speed])


def _apply_stroke(env, k, s):
    """Compensator in position mode: command the stroke (m, + up) of the plan at step k."""
    if k == 0:       # a fast position actuator: lag of one physics step, no rate limit below 10 m/s
        from towenv.core import kernels as K
        env.sim.set_compensator(mode="position")
        env.sim.comp[K.C_TAU] = env.physics_dt
        env.sim.comp[K.C_RATE] = 10.0
    env.sim.set_compensator(command=float(s[k]))
    return np.zeros(2)


# ============================================================================ identification
def identify_fir(env, kind: str, fir_seconds: float = 60.0, step: float = 0.01, seed: int = 12345):
    """Impulse response (FIR, one tap per control step) of the fish heave to the *commanded* input p — winch-line
    length change (``kind="winch"``) or stroke (``"stroke"``) — in calm water (Hs = 1 µm): the difference of a
    run with a commanded step of ``step`` m at t = 10 s and a run without, divided by the step (the simulator is
    deterministic, so the difference is the response itself; the actuator's lag is part of it). Returns
    (h, settled) where settled = |last 5 s of the step response − its final value| / |final value|."""
    from towenv.sea import SeaState
    u = copy.deepcopy(env)
    k0 = int(round(10.0 / u.dt))
    F = int(round(fir_seconds / u.dt))
    u.episode_seconds = (k0 + F + 1) * u.dt
    u.max_steps = k0 + F + 1
    n = u.max_steps
    sea = SeaState(hs=1e-6, tp=6.0)
    apply = _apply_winch if kind == "winch" else _apply_stroke
    base = _episode(u, sea, seed, np.zeros(n), apply)["heave"]
    p = np.zeros(n)
    p[k0:] = step
    g = (_episode(u, sea, seed, p, apply)["heave"] - base)[k0:k0 + F] / step
    h = np.diff(g, prepend=0.0)
    tail = g[-int(round(5.0 / u.dt)):]
    settled = float(np.max(np.abs(tail - g[-1])) / max(abs(g[-1]), 1e-12))
    return h, settled


# ============================================================================ optimisation
#: the plan's knots are every DECIMATE control steps (0.2 s); the input is linear between knots
DECIMATE = 2
#: OSQP tolerance (absolute and relative) of the planning QPs
QP_EPS = 1e-6


def _coarse_fir(h, D):
    """FIR from knot inputs to the heave at the knots: the response to a unit 'hat' input (linear
    interpolation between knots) sampled every D control steps."""
    n = h.size + 2 * D
    hat = np.zeros(n)
    hat[:D] = (np.arange(D) + 1) / D                 # rises to 1 at the knot (index D-1)...
    hat[D:2 * D] = 1.0 - (np.arange(D) + 1) / D      # ...and falls to 0 at the next knot
    y = np.convolve(hat, h)[:h.size]
    return y[D - 1::D]


def _to_fine(q, D, n):
    """Fine input of knots q (knot j at control step D·j + D − 1; 0 before the first knot)."""
    kk = np.arange(n)
    knots = np.arange(q.size) * D + D - 1
    return np.interp(kk, np.r_[-1, knots], np.r_[0.0, q])


def _qp(hc, c, q_ref, window, limits, rho, target=None):
    """min Σ_W (c + Hc q − mean)² + ρ‖q − q_ref‖²  (or ‖q − target‖² when ``target`` is given) subject to
    |q| ≤ q_max, |Δq| ≤ dq_max, |Δ²q| ≤ d2q_max (None = no limit); OSQP, sparse."""
    import osqp
    import scipy.sparse as sp
    m = c.size
    W = np.flatnonzero(window)
    nw = W.size
    F = hc.size
    qmax, dqmax, d2qmax = limits
    I = sp.eye(m, format="csc")
    D1 = sp.diags([np.ones(m), -np.ones(m - 1)], [0, -1], shape=(m, m), format="csc")
    blocks, lo, hi = [], [], []
    if target is None:
        rows, cols, vals = [], [], []
        for r, k in enumerate(W):
            i = np.arange(min(F, k + 1))
            rows.append(np.full(i.size, r))
            cols.append(k - i)
            vals.append(-hc[i])
        Hw = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(nw, m))
        blocks.append(sp.hstack([Hw, sp.eye(nw), sp.csr_matrix(np.ones((nw, 1)))], format="csc"))
        lo.append(c[W])
        hi.append(c[W])
        nz = nw + 1
        P = sp.block_diag([2.0 * rho * I, 2.0 * sp.eye(nw), sp.csc_matrix((1, 1))], format="csc")
        q = np.concatenate([-2.0 * rho * q_ref, np.zeros(nz)])
    else:
        nz = 0
        P = 2.0 * I
        q = -2.0 * target
    Z = sp.csc_matrix((m, nz))
    for M, lim in ((I, qmax), (D1, dqmax), (D1 @ D1, d2qmax)):
        if lim is not None:
            blocks.append(sp.hstack([M, Z], format="csc") if nz else M)
            lo.append(np.full(m, -lim))
            hi.append(np.full(m, lim))
    A = sp.vstack(blocks, format="csc")
    prob = osqp.OSQP()
    prob.setup(sp.csc_matrix(P), q, A, np.concatenate(lo), np.concatenate(hi), verbose=False, eps_abs=QP_EPS,
               eps_rel=QP_EPS, max_iter=20000, polishing=True)
    r = prob.solve(raise_error=False)
    x = r.x
    if x is None or not np.all(np.isfinite(x[:m])):
        raise RuntimeError(f"clairvoyant QP failed: {r.info.status}")
    return x[:m]


@dataclass
class PlanResult:
    plan: np.ndarray          # input trajectory per control step (length change or stroke, m)
    sigma: float              # simulated σ(fish heave) over the scored window, m
    history: list             # σ per iteration
    seconds: float
    free_sigma: float = math.nan   # σ with no control on the same episode (NaN for plans read from the cache)


def plan_episode(env, sea, seed, kind: str, h, iterations: int = 8, discard: float | None = None,
                 rho: float = 1e-4, margin: float = 0.97, verbose: bool = False) -> PlanResult:
    """Clairvoyant plan for one episode (module docstring). ``env``: an unwrapped WinchPayout / CompensatorGains
    environment used only for planning (its state is overwritten); ``h``: :func:`identify_fir`'s response."""
    from .metrics import default_discard
    t0 = time.time()
    discard = default_discard(env.episode_seconds) if discard is None else float(discard)
    T = env.dt
    D = DECIMATE
    n = env.max_steps
    m = n // D
    knots = np.arange(m) * D + D - 1
    window = (knots + 1) * T >= discard
    DT = D * T
    if kind == "winch":
        limits = (margin * env.winch_travel, margin * env.winch_max_speed * DT, margin * env.winch_max_acceleration * DT * DT)
        apply = _apply_winch
    else:
        limits = (margin * env.half_stroke, None, None)
        apply = _apply_stroke
    hc = _coarse_fir(h, D)

    def simulate(q):
        r = _episode(env, sea, seed, _to_fine(q, D, n), apply)
        sig = float(np.std(r["heave"][(np.arange(n) + 1) * T >= discard])) if r["ok"] else math.inf
        return sig, r

    free_sig, free = simulate(np.zeros(m))
    # feed-forward start: track the future along-cable displacement (winch) / minus the tow heave (stroke)
    target = (free["disp_along"] if kind == "winch" else -free["tow_heave"])[knots]
    if kind != "winch":
        target = target - target[window].mean()
    q = _qp(hc, np.zeros(m), np.zeros(m), window, limits, 0.0, target=target)
    sig, run = simulate(q)
    best = (sig, q, run)
    hist = [sig]
    if verbose:
        print(f"[clairvoyant] {kind}: no control σ = {free_sig:.4f} m; feed-forward plan σ = {sig:.4f} m", flush=True)
    for j in range(iterations):
        sig0, q0, run0 = best
        c = run0["heave"][knots] - np.convolve(q0, hc)[:m]
        q_new = _qp(hc, c, q0, window, limits, rho)
        improved = False
        for alpha in (1.0, 0.5, 0.25, 0.125):             # line search on the simulator itself
            q_try = q0 + alpha * (q_new - q0)
            sig, r = simulate(q_try)
            if verbose:
                print(f"[clairvoyant] {kind} iteration {j} step {alpha:g}: σ = {sig:.4f} m, "
                      f"slack {r['slack'].mean():.2f}", flush=True)
            if sig < best[0]:
                best = (sig, q_try, r)
                improved = True
                break
        hist.append(best[0])
        if not improved:
            rho *= 10.0                                    # trust the linear model less
            if rho > 1.0:
                break
    return PlanResult(_to_fine(best[1], D, n), best[0], hist, time.time() - t0, free_sig)


# ============================================================================ baselines
#: bump when the planner changes (invalidates cached plans)
PLAN_VERSION = 1


class _Clairvoyant(Baseline):
    """Common part: plans each episode at its start on a private copy of the environment."""
    KIND = "winch"
    ITERATIONS = 8
    acts_on = "env (future: the episode's sea and wave seed)"

    def __init__(self, env, iterations: int | None = None, fir_seconds: float = 60.0, verbose: bool = False,
                 cache_dir: str | None = "runs/clairvoyant_plans"):
        super().__init__(env)
        self.cache_dir = cache_dir
        iterations = self.ITERATIONS if iterations is None else iterations
        self.iterations = int(iterations)
        self.fir_seconds = float(fir_seconds)
        self.verbose = verbose
        self._planner = None
        self._h = None
        self._plans: dict = {}
        self.plan: np.ndarray | None = None
        self.last: PlanResult | None = None
        self._k = 0

    def _ensure(self):
        if self._planner is None:
            self._planner = copy.deepcopy(self.u)
            self._planner.render_mode = None
            self._h, self.fir_settled = identify_fir(self._planner, self.KIND, self.fir_seconds)

    def _cache_file(self, sea, seed):
        """Plans are cached on disk (``cache_dir``, default ``runs/clairvoyant_plans`` under the current
        directory) keyed by everything that decides them: the environment's physics and actuator keywords,
        the sea state, the wave seed, the episode length and the planner's settings."""
        if self.cache_dir is None:
            return None
        import hashlib
        import json
        u = self.u
        cfg = {k: repr(getattr(u, k, None)) for k in ("physics_dt", "dt", "max_steps", "winch_max_speed",
                                                      "winch_max_acceleration", "winch_travel",
                                                      "_half_stroke")}    # the private name keeps cached plans' keys
        cfg.update(scene=repr(u.base_scene.model_dump() if hasattr(u.base_scene, "model_dump") else u.base_scene),
                   sea=repr(sea), seed=int(seed), kind=self.KIND, iterations=self.iterations,
                   fir=self.fir_seconds, version=PLAN_VERSION)
        digest = hashlib.sha1(json.dumps(cfg, sort_keys=True).encode()).hexdigest()[:16]
        from pathlib import Path
        return Path(self.cache_dir) / f"{self.KIND}_{sea_key(sea)}_{int(seed)}_{digest}.npz"

    def reset(self):
        sea, seed = self.u.sea
        key = (sea_key(sea), round(float(sea.heading_deg), 3), int(seed), self.u.max_steps)
        if key not in self._plans:
            f = self._cache_file(sea, seed)
            if f is not None and f.exists():
                d = np.load(f)
                self._plans[key] = PlanResult(d["plan"], float(d["sigma"]), list(d["history"]), float(d["seconds"]))
            else:
                self._ensure()
                self._planner.episode_seconds = self.u.episode_seconds
                self._planner.max_steps = self.u.max_steps
                r = self._plans[key] = plan_episode(self._planner, sea, seed, self.KIND, self._h, self.iterations,
                                                    verbose=self.verbose)
                if f is not None:
                    import os
                    f.parent.mkdir(parents=True, exist_ok=True)
                    tmp = f.with_name(f".{f.name}.tmp-{os.getpid()}.npz")
                    np.savez(tmp, plan=r.plan, sigma=r.sigma, history=np.array(r.history), seconds=r.seconds)
                    os.replace(tmp, f)
        self.last = self._plans[key]
        self.plan = self.last.plan
        self._k = 0


class ClairvoyantWinch(_Clairvoyant):
    """Clairvoyant winch (module docstring): the episode's optimal length trajectory within the winch's speed,
    acceleration and travel limits, replayed as payout-speed commands."""
    name = "clairvoyant"
    kind = "winch"
    KIND = "winch"

    def act(self, obs):
        k = min(self._k, self.plan.size - 1)
        self._k += 1
        return _apply_winch(self.u, k, self.plan)

    def describe(self):
        return (f"clairvoyant winch: perfect foresight of the episode, length trajectory optimised on the simulator "
                f"within the same speed/acceleration/travel limits ({self.iterations} learning iterations)")


class ClairvoyantActiveCompensator(_Clairvoyant):
    """Upper bound for CompensatorGains (module docstring): the compensator in position mode following the
    episode's optimal stroke trajectory within the same stroke. Not a semi-active law: a bound on them."""
    name = "clairvoyant_active"
    kind = "compensator"
    KIND = "stroke"
    ITERATIONS = 12

    def act(self, obs):
        k = min(self._k, self.plan.size - 1)
        self._k += 1
        return _apply_stroke(self.u, k, self.plan)

    def describe(self):
        return (f"clairvoyant ACTIVE compensator (bound on every semi-active law): stroke trajectory optimised on the "
                f"simulator with perfect foresight within the same ±{self.u.half_stroke:g} m stroke")
