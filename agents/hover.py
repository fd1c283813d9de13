"""Hover et al. (1994) §IV-B compensator tuning rules, evaluated per sea state with the linear model.

The rules (for a compensator whose travel is limited):

* find the critical stiffness ``k_crit`` — the largest stiffness for which the towfish heave |p1(ω0)| is
  below the locked-compensator value *for every damping* (and every smaller stiffness too);
* ``min(k) < k_crit``: use the smallest stiffness and increase the damping until the compensator motion
  meets the travel limit; ``min(k) >= k_crit``: lock the compensator.

"Meets the travel" is Hover's statistical criterion: the 1/1000-highest compensator height must not
exceed the available stroke, i.e. ``|R(ω0)/D(ω0)| ≤ stroke / (1.86 H_s,deck)`` (1.86 = 2 × 3.72 / 4: the
Rayleigh 1/1000-highest height over the significant height), at the peak frequency ω0 of the tow-point
heave spectrum. ``R/D`` and ``p1/D`` come from :func:`towenv.verification.closed_forms.compensator_tf`
(Hover eq. 27, the primary cable as an axial string with an end mass).

Model inputs derived from the scene (documented assumptions, not Hover's numbers):

* string: the primary cable's length, mass per length (+ its axial added mass per length) and EA;
* end mass ``M_end``: both towed bodies' masses plus their heave added masses plus the secondary cable;
* end damping ``B_Q``: the bodies' linearised hydrodynamic heave damping at the tow speed U,
  ``Σ ½ ρ U A_ref (|dC_L/dα| + C_D(0))`` (lift-curve slope from the coefficient tables at ±5°);
  cable drag damping is neglected (``b_p = 0``) — Hover iterated drag linearisation; we do not;
* deck motion: the prescribed tow-point vertical motion for the sea state (vessel RAOs × wave record of
  a *design* seed, not the evaluation seed), ``H_s,deck = 4σ`` and ω0 = peak of its Welch spectrum.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["linear_model_params", "deck_motion_stats", "hover_design"]

RATIO_1000 = 2.0 * math.sqrt(2.0 * math.log(1000.0)) / 4.0     # 1.86


def _slope_and_cd0(coeffs):
    inc, drag, lift, _ = coeffs.full()
    inc = np.radians(np.asarray(inc, float))
    lift = np.asarray(lift, float)
    d = math.radians(5.0)
    cl = np.interp([-d, d], inc, lift)
    cd0 = float(np.interp(0.0, inc, np.asarray(drag, float)))
    return abs(cl[1] - cl[0]) / (2.0 * d), cd0


def linear_model_params(scene) -> dict:
    """Parameters of Hover's linear compensator model from a towenv scene (see the module docstring)."""
    rho = float(scene.water.density)
    U = float(scene.vessel.speed)
    roots = [ln for ln in scene.lines if ln.top_kind == "vessel"]
    prim = roots[0]
    m_line = float(prim.mass_per_length) + rho * math.pi * float(prim.diameter) ** 2 / 4.0 * float(prim.cat)
    M_end = 0.0
    B_Q = 0.0
    for b in scene.bodies:
        am = b.added_mass
        M_end += float(b.mass) + (float(am[2]) if am is not None else 0.0)
        if getattr(b, "coefficients", None) is not None and b.reference_area:
            slope, cd0 = _slope_and_cd0(b.coefficients)
            B_Q += 0.5 * rho * U * float(b.reference_area) * (slope + cd0)
    for ln in scene.lines:
        if ln is not prim:
            M_end += float(ln.mass_per_length) * float(ln.length)
    comp = scene.compensator
    return {"L": float(prim.length), "m": m_line, "EA": float(prim.EA), "M_end": M_end, "B_Q": B_Q,
            "m_c": float(comp.mass) if comp is not None else 0.0}


def deck_motion_stats(scene, sea, seed: int, duration: float = 1800.0, dt: float = 0.1, t_start: float = 60.0):
    """(H_s,deck (m), ω0 (rad/s)) of the prescribed tow-point vertical motion in ``sea`` (wave seed
    ``seed``): the vessel motion only, no cable simulation."""
    from towenv.core.simulator import Simulator
    from towenv.stats import welch_psd
    sim = Simulator(scene, dt=0.05)
    sim.set_sea(sea, int(seed))
    t = np.arange(t_start, t_start + duration, dt)
    z = sim.path.position(t)[:, 2]
    z = z - z.mean()
    w, S = welch_psd(z, dt, nperseg=2048)
    sel = w > 0.2
    w0 = float(w[sel][np.argmax(S[sel])])
    return 4.0 * float(np.std(z)), w0


def hover_design(scene, sea, seed: int, k_bounds=None, b_bounds=None, n_grid: int = 61) -> dict:
    """Hover's tuning decision for one sea state: ``{"mode": "passive"|"locked", "stiffness", "damping",
    "k_crit", "H_deck", "omega0", "R_max", ...}``."""
    from towenv.verification.closed_forms import compensator_tf
    comp = scene.compensator
    p = linear_model_params(scene)
    H, w0 = deck_motion_stats(scene, sea, seed)
    klo, khi = k_bounds or comp.stiffness_bounds
    blo, bhi = b_bounds or comp.damping_bounds
    klo = max(float(klo), 1e-3 * float(khi))
    blo_eff = max(float(blo), 1e-3 * float(bhi))
    ks = np.geomspace(klo, float(khi), n_grid)
    bs = np.concatenate([[0.0], np.geomspace(blo_eff, float(bhi), n_grid)])
    if blo > 0:
        bs = bs[1:]
    args = dict(L=p["L"], m=p["m"], EA=p["EA"], M_end=p["M_end"], m_c=p["m_c"], B_Q=p["B_Q"])
    locked = abs(complex(compensator_tf(np.array([w0]), k_c=np.inf, **args).p1[0]))
    p1 = np.empty((ks.size, bs.size))
    R = np.empty_like(p1)
    for i, k in enumerate(ks):
        for j, b in enumerate(bs):
            tf = compensator_tf(np.array([w0]), k_c=float(k), b_c=float(b), **args)
            p1[i, j] = abs(complex(tf.p1[0]))
            R[i, j] = abs(complex(tf.R[0]))
    ok = (p1 < locked).all(axis=1)
    # k_crit: largest k with every k' <= k below the locked value for all b
    if ok[0]:
        last = int(np.argmin(ok)) - 1 if not ok.all() else ks.size - 1
        k_crit = float(ks[last])
    else:
        k_crit = 0.0
    r_max = float(comp.stroke) / (RATIO_1000 * H) if H > 0 else math.inf
    out = {"k_crit": k_crit, "H_deck": H, "omega0": w0, "R_max": r_max, "p1_locked": locked,
           "model": {k: round(float(v), 3) for k, v in p.items()}, "design_seed": int(seed)}
    if klo < k_crit:
        feasible = np.flatnonzero(R[0] <= r_max)
        if feasible.size:
            j = int(feasible[0])
            b = float(bs[j])
            out.update(mode="passive", stiffness=float(ks[0]), damping=max(b, float(blo)),
                       p1_ratio=float(p1[0, j] / locked), R_ratio=float(R[0, j]))
            return out
        out.update(mode="locked", reason="no damping meets the travel limit at the smallest stiffness")
        return out
    out.update(mode="locked", reason="min(k) >= k_crit")
    return out
