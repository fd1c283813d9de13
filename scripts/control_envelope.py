#!/usr/bin/env python
"""The operating envelope of the WinchPayout / CompensatorGains scene: what the sea asks of the actuator.

For each sea state of the evaluation set (coastal WMO codes 3-5, four headings each) with the winch held fixed
(no compensation), prints: the tow point's significant heave (4σ of the MRU heave), the significant along-cable
displacement, the RMS and 99.9th-percentile along-cable velocity and acceleration (what a payout that cancels
the along-cable motion must deliver), the fraction of time that demand exceeds each winch class's speed and
acceleration limits, the static tension of the secondary cable and the fraction of time a segment is slack.

    python scripts/control_envelope.py [--seed-offset 0] [--replicates 1]

Uses only the public environment API; about 20 s.
"""
from __future__ import annotations

import argparse
import sys

import numpy as np


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seed-offset", type=int, default=0, help="added to the evaluation wave seeds")
    p.add_argument("--replicates", type=int, default=1)
    args = p.parse_args(argv)
    import gymnasium as gym
    import towenv.envs  # noqa: F401
    from towenv.envs.winch import WINCH_CLASSES
    env = gym.make("towenv/WinchPayout-v0")
    u = env.unwrapped
    rows = {}
    for i, (sea, seed) in enumerate(u.eval_sea_states()):
        code = u.sea_codes[i // 4]
        for r in range(args.replicates):
            s = seed + args.seed_offset + 100 * r
            env.reset(seed=s, options={"sea_state": sea, "sea_seed": s})
            sec = u.sim.tensions[u.sim.system.line("secondary").segments]
            rec = {k: [] for k in ("tow_heave", "tow_disp_along", "tow_vel_along", "tow_acc_along", "slack")}
            for k in range(u.max_steps):
                _, _, _, _, info = env.step(np.zeros(1, np.float32))
                m = u._last_m
                if m["t"] < 60.0:
                    continue
                for c in ("tow_heave", "tow_disp_along", "tow_vel_along", "tow_acc_along"):
                    rec[c].append(m[c])
                rec["slack"].append(info["slack"])
            d = rows.setdefault(code, {"static_secondary": float(np.mean(sec)), "hs": sea.hs, "tp": sea.tp, "x": []})
            d["x"].append({k: np.asarray(v) for k, v in rec.items()})
    hdr = ["code", "Hs m", "Tp s", "sig. tow heave m", "sig. along disp m", "v_al RMS / 99.9 % m/s",
           "a_al RMS / 99.9 % m/s²"] + [f"{n}: v>{c['max_speed']:g} / a>{c['max_acceleration']:g}"
                                          for n, c in WINCH_CLASSES.items()] + ["secondary static T N", "slack"]
    print("| " + " | ".join(hdr) + " |")
    print("|" + "---|" * len(hdr))
    for code, d in rows.items():
        cat = {k: np.concatenate([x[k] for x in d["x"]]) for k in d["x"][0]}
        v, a = np.abs(cat["tow_vel_along"]), np.abs(cat["tow_acc_along"])
        cells = [str(code), f"{d['hs']:.2f}", f"{d['tp']:.2f}", f"{4 * cat['tow_heave'].std():.2f}",
                 f"{4 * cat['tow_disp_along'].std():.2f}",
                 f"{np.sqrt(np.mean(v ** 2)):.2f} / {np.quantile(v, 0.999):.2f}",
                 f"{np.sqrt(np.mean(a ** 2)):.2f} / {np.quantile(a, 0.999):.2f}"]
        for c in WINCH_CLASSES.values():
            cells.append(f"{100 * np.mean(v > c['max_speed']):.1f} % / {100 * np.mean(a > c['max_acceleration']):.1f} %")
        cells += [f"{d['static_secondary']:.0f}", f"{100 * cat['slack'].mean():.0f} %"]
        print("| " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
