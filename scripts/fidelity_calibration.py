"""How well does the fidelity selection's linear error prediction match the nonlinear simulator?

For each case of ``scripts/fidelity_check.py`` with the given roles (default: build and tuned — never the
held-out cases), the fine default is run once, then a ladder of configurations (segment factors × time steps,
2-D where the selection would allow it) is run and the measured relative error of the fish heave and pitch
standard deviations (300 s, statistics from t = 60 s, same seed) is compared with the *raw* prediction of
:func:`towenv.fidelity.select` (its two components, the segment part and the time-step part, without the
safety factor). Prints one line per run and a summary of measured / predicted; ``--out`` saves the rows as JSON.

    python scripts/fidelity_calibration.py [--roles build,tuned] [--out calib.json]
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from fidelity_check import CASES, fish_name, fish_stats  # noqa: E402
from towenv import fidelity as F  # noqa: E402
from towenv.core.run import simulate  # noqa: E402
from towenv.core.simulator import load  # noqa: E402

LADDER_DT = (0.03, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3)
LADDER_F = (1.0, 2.0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--roles", default="build,tuned")
    ap.add_argument("--duration", type=float, default=300.0)
    ap.add_argument("--cases", default="", help="comma-separated case indices into fidelity_check.CASES")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    roles = set(args.roles.split(","))
    if "held-out" in roles:
        ap.error("--roles: the held-out cases are not used for calibration")
    idx = [int(i) for i in args.cases.split(",") if i] or range(len(CASES))
    cases = [CASES[i] for i in idx if CASES[i][3] in roles]
    rows = []
    simulate(load(cases[0][1]), 5.0)
    for label, name, ov, role in cases:
        base = load(name).with_overrides(ov) if ov else load(name)
        fish = fish_name(base)
        try:
            ch = F.select(base, tolerance=0.5, safety=1.0, pilot=False, allow_linear=False)
        except Exception as exc:  # noqa: BLE001
            print(f"{label}: no prediction ({exc})", flush=True)
            continue
        t = time.perf_counter()
        try:
            ref = fish_stats(simulate(base.with_overrides(F.fine_default(base).overrides()), args.duration),
                             fish, 60.0)
        except Exception as exc:  # noqa: BLE001
            print(f"{label}: fine default failed ({exc})", flush=True)
            continue
        ref_wall = time.perf_counter() - t
        planar = any(c.planar for c in ch.candidates)
        # components: re-run the prediction with only the segment part / only the time-step part
        seg_only = F.select(base, tolerance=0.5, safety=1.0, pilot=False, allow_linear=False,
                            dt_candidates=(F.fine_time_step(base),))
        seg_err = {c.segment_factor: c.predicted_error for c in seg_only.candidates}
        for c in ch.candidates:
            if c.segment_factor not in LADDER_F or not any(abs(c.dt - d) < 1e-9 for d in LADDER_DT):
                continue
            t = time.perf_counter()
            try:
                got = fish_stats(simulate(base.with_overrides(c.overrides()), args.duration), fish, 60.0)
                wall = time.perf_counter() - t
            except Exception as exc:  # noqa: BLE001
                print(f"{label} f {c.segment_factor:g} dt {c.dt:g}: failed ({str(exc)[:80]})", flush=True)
                rows.append(dict(case=label, f=c.segment_factor, dt=c.dt, failed=str(exc)[:200]))
                continue
            meas = {k: abs(got[k] / ref[k] - 1.0) for k in got if k in c.predicted_error and ref[k] > 0}
            row = dict(case=label, f=c.segment_factor, dt=c.dt, planar=planar, pred=c.predicted_error,
                       pred_seg=seg_err.get(c.segment_factor, {}), meas=meas, wall=wall, ref_wall=ref_wall)
            rows.append(row)
            pm = max(c.predicted_error.values())
            mm = max(meas.values())
            print(f"{label[:50]:50s} f {c.segment_factor:3g} dt {c.dt:5.3f}  pred {100 * pm:6.2f} %  "
                  f"meas {100 * mm:6.2f} %  ratio {mm / max(pm, 1e-12):6.2f}  speed-up {ref_wall / wall:5.1f}",
                  flush=True)
    if args.out:
        args.out.write_text(json.dumps(rows, indent=1))
    ok = [r for r in rows if "meas" in r and max(r["pred"].values()) > 0.005]
    if ok:
        ratios = np.array([max(r["meas"].values()) / max(r["pred"].values()) for r in ok])
        print(f"\nmeasured / predicted (raw, predicted > 0.5 %, {len(ok)} runs): median {np.median(ratios):.2f}, "
              f"90th percentile {np.percentile(ratios, 90):.2f}, 95th {np.percentile(ratios, 95):.2f}, "
              f"max {ratios.max():.2f}")


if __name__ == "__main__":
    main()
