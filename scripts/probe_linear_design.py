"""Probe: design the ARS policy's linear residual in one shot from an identified linear model, and check it on the
simulator — with the default (standard) winch and with a winch whose limits never bind.

Issue 14 asks what limits a causal controller. The ARS residual (agents/ars.py) is a = a_along(obs) + θ·φ. Its
exogenous features — the MRU's along-cable velocity, acceleration and displacement over the last 2 s, and a
constant — do not depend on the winch, so if the fish heave responded linearly to the commanded line length, θ
would follow from one least-squares problem:

1. identify the closed-loop impulse response h (commanded length change → fish heave and pitch) in calm water, with
   the along-cable law's feedback active (its per-sea-state gains), by a 1 cm step of the residual;
2. run the along-cable law (θ = 0) on design episodes, record y (heave, pitch) and the features Φ;
3. the residual's length change is ΔL = Δt·v_max·cumsum(Φθ), so y(θ) = y + G θ with G = h * (Δt·v_max·cumsum Φ);
   minimise Σ_e ‖P(y_e + G_e θ)‖²/σ_e² + 0.5·(the same for pitch) + λ‖θ‖² (P removes the scored window's mean);
4. simulate the designed θ on fresh check episodes against the along-cable law on the same waves.

Run (one core, ~4 min per winch):

    python scripts/probe_linear_design.py                                                  # standard winch
    python scripts/probe_linear_design.py --winch-max-speed 10 --winch-max-acceleration 50  # limits never bind

Wave seeds: design 1000·code + j + 75000 + 100 r, check + 76000 + 100 r — never an evaluation, tuning, validation,
final or ARS-training seed.
"""
from __future__ import annotations

import argparse
import copy
import math
import time

import numpy as np

DESIGN_OFFSET, CHECK_OFFSET = 75000, 76000
PITCH_WEIGHT = 0.5


def _fftconv(h, X):
    """Causal convolution of every column of X (T, ...) with h, truncated to T."""
    T = X.shape[0]
    nfft = 1 << int(math.ceil(math.log2(T + h.size)))
    Hf = np.fft.rfft(h, nfft)
    return np.fft.irfft(Hf.reshape((-1,) + (1,) * (X.ndim - 1)) * np.fft.rfft(X, nfft, axis=0), nfft, axis=0)[:T]


def identify_closed_loop(env, gains: dict, fir_seconds: float = 60.0, step: float = 0.01):
    """(h_heave, h_pitch): response per control step to a commanded length step of the residual, with the along-cable
    law (``gains``) acting, in calm water (Hs 1 µm); difference of a run with and without the step."""
    from agents.classical import AlongCableWinch, along_cable_velocity
    from agents.common import ObsReader
    from towenv.sea import SeaState
    u = copy.deepcopy(env.unwrapped)
    reader = ObsReader(env)
    k0, F = int(round(10.0 / u.dt)), int(round(fir_seconds / u.dt))
    u.episode_seconds, u.max_steps = (k0 + F + 1) * u.dt, k0 + F + 1
    runs = []
    for s in (0.0, step):
        obs, _ = u.reset(seed=12345, options={"sea_state": SeaState(hs=1e-6, tp=6.0), "sea_seed": 12345})
        y, p = np.empty(u.max_steps), np.empty(u.max_steps)
        for k in range(u.max_steps):
            v_res = s / u.dt if k == k0 else 0.0
            v = along_cable_velocity(*(gains[g] for g in ("g_ff", "tau", "kl", "kp", "kd")),
                                     *(reader(obs, c) for c in AlongCableWinch.CHANNELS))
            obs, _, _, _, info = u.step(np.array([(v + v_res) / u.winch_max_speed], np.float32))
            y[k], p[k] = info["fish_heave"], info["fish_pitch"]
        runs.append((y, p))
    hy = np.diff((runs[1][0] - runs[0][0])[k0:k0 + F] / step, prepend=0.0)
    hp = np.diff((runs[1][1] - runs[0][1])[k0:k0 + F] / step, prepend=0.0)
    return hy, hp


def _rollout(venv, batch, seas, seeds, theta, record: bool):
    from agents.common import reset_copies
    n = venv.num_envs
    obs = reset_copies(venv, seas, seeds)
    batch.set_seas(seas)
    T = venv.envs[0].max_steps
    H, P, t = np.zeros((T, n)), np.zeros((T, n)), np.zeros(T)
    PHI = np.zeros((T, n, theta.shape[1]), np.float32) if record else None
    FREE = np.zeros((T, n), bool) if record else None
    CMD = np.zeros((T, n))
    for k in range(T):
        phi = batch.features(obs, k == 0)
        raw = batch.base_action(obs) + np.einsum("nf,nf->n", theta, phi)
        if record:
            PHI[k], FREE[k] = phi, np.abs(raw) < 1.0
        CMD[k] = np.clip(raw, -1.0, 1.0)
        obs, _r, _te, _tr, infos = venv.step(CMD[k].astype(np.float32)[:, None])
        H[k], P[k], t[k] = infos["fish_heave"], infos["fish_pitch"], infos["t"][0]
    return H, P, t, PHI, FREE, CMD


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--winch-max-speed", type=float, default=None, help="m/s (default: the standard winch)")
    ap.add_argument("--winch-max-acceleration", type=float, default=None, help="m/s² (default: the standard winch)")
    ap.add_argument("--design-replicates", type=int, default=8, help="design wave seeds per (sea state, heading)")
    ap.add_argument("--check-replicates", type=int, default=2, help="check wave seeds per (sea state, heading)")
    ap.add_argument("--ridge", type=float, nargs="+", default=[1e-3, 1e-2, 1e-1, 1.0],
                    help="ridge weights λ (relative to the normal matrix's mean diagonal); the check runs each")
    a = ap.parse_args(argv)
    import gymnasium as gym
    import towenv  # noqa: F401
    from agents import ars
    from agents.baselines import load_tuned
    from agents.classical import DEFAULT_ALONG_GAINS
    from agents.common import nearest_key
    from towenv.envs.vector import WinchPayoutVectorEnv
    t0 = time.time()
    kw = {k: v for k, v in (("winch_max_speed", a.winch_max_speed),
                            ("winch_max_acceleration", a.winch_max_acceleration)) if v is not None}
    table = dict(load_tuned()["along_cable"])
    env = gym.make(ars.ENV_ID, **kw)
    u = env.unwrapped
    print(f"winch: max speed {u.winch_max_speed:g} m/s, max acceleration {u.winch_max_acceleration:g} m/s²", flush=True)
    ev = u.eval_sea_states()
    keys = sorted(table)
    fs = "v2"
    nf = ars.n_features(fs)
    exo = np.r_[np.arange(len(ars.HISTORY_CHANNELS) * len(ars.LAG_STEPS)), nf - 1]     # MRU history + constant
    fir = {k: identify_closed_loop(env, DEFAULT_ALONG_GAINS | table[k]) for k in keys}

    def episodes(offset, reps):
        seas, seeds, code = [], [], []
        for r in range(reps):
            for sea, s in ev:
                seas.append(sea)
                seeds.append(int(s) + offset + 100 * r)
                code.append(keys.index(nearest_key(table, sea)))
        return seas, seeds, np.array(code)

    seas, seeds, code = episodes(DESIGN_OFFSET, a.design_replicates)
    n = len(seas)
    venv = WinchPayoutVectorEnv(num_envs=n, autoreset_mode="NextStep", batch_infos=True, **kw)
    batch = ars._Batch(venv, table, dict(ars.FEATURE_SCALES), fs)
    H, P, t, PHI, FREE, CMD = _rollout(venv, batch, seas, seeds, np.zeros((n, nf)), True)
    venv.close()
    w = t >= 60.0
    acc = np.diff(CMD, axis=0)[t[1:] >= 10.0] * u.winch_max_speed / u.dt
    print(f"the along-cable law's commanded acceleration exceeds the winch's {u.winch_max_acceleration:g} m/s² in "
          f"{100 * np.mean(np.abs(acc) > u.winch_max_acceleration):.1f} % of the design steps after 10 s", flush=True)
    dL = u.dt * u.winch_max_speed * np.cumsum(PHI[:, :, exo].astype(float) * FREE[:, :, None], axis=0)
    Gy, Gp = np.empty((int(w.sum()), n, exo.size)), np.empty((int(w.sum()), n, exo.size))
    for c, k in enumerate(keys):
        i = np.flatnonzero(code == c)
        Gy[:, i], Gp[:, i] = _fftconv(fir[k][0], dL[:, i])[w], _fftconv(fir[k][1], dL[:, i])[w]
    Gy -= Gy.mean(0)
    Gp -= Gp.mean(0)
    y, p = H[w] - H[w].mean(0), P[w] - P[w].mean(0)
    sy, sp = y.std(0), p.std(0)
    fit = np.arange(n) < n // 2
    designs = {}
    print(f"design: {n} along-cable episodes ({time.time() - t0:.0f} s); linear model's prediction, heave / pitch σ "
          f"ratio to along_cable (first half fitted, second half held out):", flush=True)
    for lam in a.ridge:
        th = np.zeros((len(keys), nf))
        line = []
        for c, k in enumerate(keys):
            i = np.flatnonzero((code == c) & fit)
            Am = sum(Gy[:, e].T @ Gy[:, e] / sy[e] ** 2 + PITCH_WEIGHT * Gp[:, e].T @ Gp[:, e] / sp[e] ** 2 for e in i)
            b = sum(Gy[:, e].T @ y[:, e] / sy[e] ** 2 + PITCH_WEIGHT * Gp[:, e].T @ p[:, e] / sp[e] ** 2 for e in i)
            th[c, exo] = -np.linalg.solve(Am + lam * np.trace(Am) / exo.size * np.eye(exo.size), b)
            j = np.flatnonzero((code == c) & ~fit)
            ry = np.mean([np.std(y[:, e] + Gy[:, e] @ th[c, exo]) / sy[e] for e in j])
            rp = np.mean([np.std(p[:, e] + Gp[:, e] @ th[c, exo]) / sp[e] for e in j])
            line.append(f"{k} {ry:.3f} / {rp:.3f}")
        designs[lam] = th
        print(f"  λ {lam:g}: " + "; ".join(line), flush=True)
    seas, seeds, code = episodes(CHECK_OFFSET, a.check_replicates)
    m = len(seas)
    lams = list(designs)
    venv = WinchPayoutVectorEnv(num_envs=m * (len(lams) + 1), autoreset_mode="NextStep", batch_infos=True, **kw)
    batch = ars._Batch(venv, table, dict(ars.FEATURE_SCALES), fs)
    theta = np.concatenate([np.zeros((m, nf))] + [designs[lam][code] for lam in lams])
    H, P, t, _, _, _ = _rollout(venv, batch, seas * (len(lams) + 1), seeds * (len(lams) + 1), theta, False)
    venv.close()
    w = t >= 60.0
    sh, sq = H[w].std(0).reshape(-1, m), P[w].std(0).reshape(-1, m)
    print(f"check on the simulator: {m} fresh episodes per design, σ ratio to along_cable on the same waves "
          f"(heave / pitch; {time.time() - t0:.0f} s):", flush=True)
    for j, lam in enumerate(lams, start=1):
        parts = [f"{k} {sh[j][code == c].mean() / sh[0][code == c].mean():.3f} / "
                 f"{sq[j][code == c].mean() / sq[0][code == c].mean():.3f}" for c, k in enumerate(keys)]
        print(f"  λ {lam:g}: " + "; ".join(parts) + f"; pooled {sh[j].mean() / sh[0].mean():.3f} / "
              f"{sq[j].mean() / sq[0].mean():.3f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
