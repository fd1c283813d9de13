"""The mean of the weights of CompensatorGains policies of one class (agents.ars_compensator.average_policies), e.g.
two Gauss-Newton chains from one ARS start with disjoint training seeds (docs/agents.md "Averaging two chains"), or
the iterates of one chain (``scripts/train_gn_compensator.py --save-iterates``; ``--features hsfo`` writes an earlier
stage's iterates in the last stage's feature set first):

    python scripts/average_compensator.py --seed 0 --export runs/chain/gnsm_CompensatorGains-v0_s0.npz runs/chain/gnsp_CompensatorGains-v0_s0.npz runs/chain/gnsp_CompensatorGains-v0_s1.npz

scripts/training_cost.py adds up the average's training cost from its members, looked up next to the average, and
their --init chains next to them, then in the folders given to its ``--search`` (e.g. ``--search agents/trained
runs/chain``): write the average into the members' folder (``--export``), or name their folders there; the default,
runs/average_CompensatorGains-v0_s<seed>.npz under the current folder, says so when the members lie elsewhere.
"""
import argparse
import sys
from pathlib import Path

from agents import ars_compensator as arc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("policies", nargs="+", help="CompensatorGains ARS / Gauss-Newton policy files (.npz), at least 2")
    ap.add_argument("--seed", type=int, required=True, help="the label of the average (its members keep their own)")
    ap.add_argument("--features", default=None, choices=arc.FEATURE_SETS,
                    help="write every member in this feature set first (agents.ars_compensator.lift_policy: the "
                         "features a member lacks at weight 0), e.g. hsfo to average the iterates of a chain's hsf "
                         "and hsfo stages; it must contain every member's features")
    ap.add_argument("--export", default=None,
                    help="output .npz, written atomically (default runs/average_CompensatorGains-v0_s<seed>.npz under "
                         "the current folder)")
    a = ap.parse_args(argv)
    if a.export is None:
        a.export = f"runs/average_CompensatorGains-v0_s{a.seed}.npz"
    if len(a.policies) < 2:
        ap.error(f"policies: give at least 2 files to average (got {len(a.policies)})")
    if not a.export.endswith(".npz"):
        ap.error(f"--export must name an .npz file (got {a.export!r})")
    if any(Path(a.export).stem == Path(p).stem for p in a.policies):
        ap.error(f"--export {a.export!r} has the name of a member: the average would overwrite it (or, next to it, "
                 "stand for it in scripts/training_cost.py); give it its own name")
    members = []
    for p in a.policies:
        try:
            members.append(arc.load_policy(p))
        except (OSError, ValueError) as exc:
            ap.error(f"{p}: {exc}")
    try:
        if a.features:
            members = [arc.lift_policy(m, a.features) for m in members]
        avg = arc.average_policies(members, a.seed)
    except ValueError as exc:
        ap.error(str(exc))
    Path(a.export).parent.mkdir(parents=True, exist_ok=True)
    out = arc.save_policy(avg, a.export)
    print(f"[average] wrote {out}: mean of {', '.join(m.name for m in members)}", flush=True)
    away = sorted({str(Path(p).parent) for p in a.policies if Path(p).resolve().parent != Path(out).resolve().parent})
    if away:
        print("[average] note: its members are not in its folder: scripts/training_cost.py adds up its cost with "
              f"--search {' '.join(away)} (it looks next to the average first)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
