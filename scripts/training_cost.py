"""Training cost of committed ARS / Gauss–Newton policy files, following each file's ``--init`` chain (issue 14's
"≤ 1 h wall per seed" recipe goal). For every file: its own wall time (the sum of ``meta["curve"][*]["seconds"]``,
the time of its iterations) and env steps, and the totals of the whole chain it continues (the ``init`` named in its
hyperparameters, looked up next to it, then in the ``--search`` folders in their order; for a weight average, every
member's chain with their shared start once):

    python scripts/training_cost.py agents/trained/gnq2_WinchPayout-v0_s{0,1,2}.npz agents/trained/gn_CompensatorGains-v0_s{0,1,2}.npz
    python scripts/training_cost.py runs/gnspfr/gnspfr_CompensatorGains-v0_s0.npz --search agents/trained

The wall times are what the runs took as they were run (three seeds side by side on two cores here), not CPU time.
"""
import argparse
import json
import sys
from pathlib import Path

import numpy as np


def read_meta(path) -> dict:
    """The metadata of an ARS / Gauss–Newton policy file; ValueError naming the file if it has none."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            return json.loads(str(z["meta"]))
    except (OSError, KeyError, ValueError) as exc:
        raise ValueError(f"{path}: not an ARS / Gauss-Newton policy file with metadata ({exc})") from None


def own_cost(meta) -> tuple[float, int]:
    """(wall seconds of the file's own iterations, its own env steps)."""
    curve = meta.get("curve") or []
    seconds = float(sum(float(c.get("seconds", 0.0)) for c in curve if isinstance(c, dict)))
    return seconds, int(meta.get("num_timesteps", 0))


def _find(path: Path, name: str, search, what: str) -> Path:
    """The policy file ``name`` (a stem or file name) of ``path``'s chain: next to ``path``, else in the first of the
    ``search`` folders that has it; ValueError naming ``what`` and every place looked in if none has it."""
    places = [path.parent] + [Path(d) for d in search]
    for d in places:
        nxt = d / f"{Path(name).stem}.npz"
        if nxt.exists():
            return nxt
    raise ValueError(f"{path}: its {what} {name!r} is not next to it"
                     + (f" nor in {', '.join(str(d) for d in places[1:])}" if len(places) > 1 else "")
                     + f" ({places[0] / (Path(name).stem + '.npz')}; --search adds folders to look in)")


def chain(path, _inside=frozenset(), search=()) -> list[tuple[str, float, int]]:
    """[(file stem, own wall seconds, own env steps)] from the first run of the chain to ``path`` (each link looked
    up next to the file that names it, then in the ``search`` folders). A weight average (``meta["averaged_from"]``,
    scripts/average_compensator.py) costs its members' chains, looked up the same way, a run they share (their common
    start) counted once, then itself (no iterations of its own). Members that are iterates of one run
    (``meta["iterate_of"]``, ``train_gn_compensator.py --save-iterates``) are parts of that run: it counts once,
    as its longest part (most env steps; the run's own file when a chain holds it and the last iterate is as long -
    an iterate file re-run from the same start carries its own re-run's wall)."""
    path = Path(path)
    members = read_meta(path).get("averaged_from")
    if members:
        if path.stem in _inside or path.stem in {Path(m).stem for m in members}:
            raise ValueError(f"{path}: the weight average lists itself among its members (directly or through one)")
        runs = {}                           # run -> its longest part among the members (dicts keep first-seen order)
        for m in members:
            nxt = _find(path, m, search, "member")
            mine = chain(nxt, _inside | {path.stem}, search)
            run_of_member = read_meta(nxt).get("iterate_of") or mine[-1][0]
            for key, run in [(r[0], r) for r in mine[:-1]] + [(run_of_member, mine[-1])]:
                held = runs.get(key)
                if (held is None or run[2] > held[2]                 # more env steps: a longer part of the run
                        or (run[2] == held[2] and run[0] == key != held[0])):   # the whole run: its own file
                    runs[key] = run
        return list(runs.values()) + [(path.stem, *own_cost(read_meta(path)))]
    out, seen = [], set()
    while True:
        if path.stem in seen:
            raise ValueError(f"{path}: its --init chain loops back to {path.stem}")
        seen.add(path.stem)
        meta = read_meta(path)
        out.append((path.stem, *own_cost(meta)))
        init = (meta.get("hyperparameters") or {}).get("init")
        if not init:
            return out[::-1]
        path = _find(path, init, search, "--init")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("policies", nargs="+", help="ARS / Gauss-Newton policy files (.npz)")
    ap.add_argument("--search", nargs="+", default=[], metavar="DIR",
                    help="folders to look in for a chain's --init files and average members not next to the file "
                         "that names them (in this order)")
    a = ap.parse_args(argv)
    for d in a.search:
        if not Path(d).is_dir():
            ap.error(f"--search: {d} is not a folder")
    for p in a.policies:
        try:
            runs = chain(p, search=a.search)
        except ValueError as exc:
            ap.error(str(exc))
        total_s, total_n = sum(r[1] for r in runs), sum(r[2] for r in runs)
        parts = " + ".join(f"{stem} {s / 60:.1f} min" for stem, s, _n in runs)
        print(f"{Path(p).stem}: chain {total_s / 60:.1f} min wall, {total_n / 1e6:.1f} M env steps ({parts})", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
