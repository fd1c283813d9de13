"""Evaluate a policy and every baseline on the evaluation sea states; write a report.

POLICY is a policy zip written by scripts/train.py (algorithm and environment from its metadata), an ARS
policy .npz written by scripts/train_ars.py or scripts/train_ars_compensator.py (told apart by the env_id and
algo of its metadata), any SB3 zip (give --algo and --env), or a baseline name (then
--env is needed). Every controller runs the
same episodes: ``env.unwrapped.eval_sea_states()`` (12 = WMO codes 3-5 × 4 headings), optionally with
extra wave seeds per entry (--replicates). Writes ``<out-dir>/<name>/report.md``, ``summary.png``,
``psd.png``, ``timeseries.png``, ``metrics.csv``, ``summary.json`` (+ ``report.html``), each file
atomically and summary.json last.

Hygiene:
  * --out-dir defaults to runs/reports under the current directory; an existing report folder is
    refused (exit 2) unless --force. The committed reports are written only with an explicit
    --out-dir docs/reports (and --force to replace one).
  * goal verdicts (MET / not met) need at least 24 episodes (agents.report.MIN_VERDICT_EPISODES,
    e.g. --replicates 2); with fewer the figures are printed with "no verdict: N episodes < 24".
  * --seed-set final: the same (Hs, Tp, heading) entries with fresh wave seeds 1000·code + j + 20000
    (+ 100 r per replicate), never used in tuning (+500), the Hover design (+900), training validation
    (+700) or the eval set (+0..+400): for the final numbers. --seed-set eval (default): 1000·code + j
    + 100 r, the set the policies were selected on.
  * policies named <family>_s<k> / <family>_seed<k> form a seed group; with two or more members the
    report gets a section "Across training seeds" (IQM and stratified-bootstrap CIs, agents/aggregate.py).
  * --reuse clairvoyant=REPORT_DIR takes a baseline's per-episode rows from an earlier report instead of
    running it (the clairvoyant winch plans cost ~2 min per episode): refused (exit 2) unless that report
    holds the same episodes and start-up window and every controller both runs share agrees with it in
    every episode (RMS heave to 1e-5 relative; metrics.csv keeps 6 digits); the report says so.

Examples::

    python scripts/evaluate.py agents/trained/ppo_WinchPayout-v0_s0.zip --replicates 2 --seed-set final
    python scripts/evaluate.py agents/trained/ppo_WinchPayout-v0_s0.zip \\
        --also agents/trained/ppo_WinchPayout-v0_s1.zip agents/trained/ppo_WinchPayout-v0_s2.zip --replicates 2
    python scripts/evaluate.py pd_ff --env towenv/WinchPayout-v0 --name winch_baselines
    python scripts/evaluate.py agents/trained/ppo_CompensatorGains-v0_s0.zip --episodes 0 4 \\
        --env-kwargs episode_seconds:40                                           # quick look
    python scripts/evaluate.py agents/trained/ppo_WinchPayout-v0_s0.zip --replicates 2 --html \\
        --out-dir docs/reports --force                                   # replace the committed report
"""
from __future__ import annotations

import argparse
import contextlib
import inspect
import os
import shlex
import sys
from pathlib import Path

# one thread per process for the command line (set before numpy/numba load their pools). Imported into a
# process that has already loaded numba (a test, a notebook), NUMBA_NUM_THREADS is left alone: numba re-reads
# its configuration at every compilation and refuses a thread count that differs from the pool it launched
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    if _v != "NUMBA_NUM_THREADS" or "numba" not in sys.modules:
        os.environ.setdefault(_v, "1")


#: keywords of a policy's training environment that are not carried to the evaluation environment
TRAINING_ONLY = ("reward_weights", "reward_fn", "episode_seconds", "sea_generator", "render_mode")

#: default report folder, relative to the current working directory
DEFAULT_OUT_DIR = os.path.join("runs", "reports")

#: wave-seed offset of each evaluation seed set, added to the evaluation list's seeds 1000·code + j
SEED_SETS = {"eval": 0, "final": 20000}
#: seed offsets used elsewhere, never to be evaluated on for final numbers: baseline tuning
#: (agents/tuning.py), the Hover design (tuning seed + 400), training validation (scripts/train.py)
RESERVED_OFFSETS = {"tuning": 500, "hover design": 900, "training validation": 700}
#: wave-seed step between replicates of one entry
REPLICATE_STEP = 100
#: most replicates of the eval set (its seeds then stay below the tuning seeds, + 500)
MAX_EVAL_REPLICATES = RESERVED_OFFSETS["tuning"] // REPLICATE_STEP


class _Parser(argparse.ArgumentParser):
    def error(self, message):                   # one line on stderr, exit 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def _fail(message: str):
    """Bad command-line input: one line on stderr and exit code 2 (as argparse does)."""
    print(f"evaluate.py: error: {message}", file=sys.stderr, flush=True)
    raise SystemExit(2)


def parse_args(argv=None):
    p = _Parser(prog="evaluate.py", description=__doc__.split("\n\n")[0],
                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("policy", help="policy zip, ARS policy .npz, or a baseline name")
    p.add_argument("--also", nargs="*", default=[], help="more policy zips / .npz in the same report")
    p.add_argument("--algo", default=None, help="algorithm of a zip without towenv metadata (ppo, sac, ...)")
    p.add_argument("--env", default=None, help="environment id (default: from the zip's metadata)")
    p.add_argument("--baselines", nargs="*", default=None, help="baselines to include (default: all of the env)")
    p.add_argument("--env-kwargs", nargs="*", default=None, metavar="KEY:VALUE",
                   help="evaluation environment keywords (Python literals), e.g. episode_seconds:60")
    p.add_argument("--episodes", nargs="*", type=int, default=None,
                   help="indices into eval_sea_states() to use (default all)")
    p.add_argument("--replicates", type=int, default=1,
                   help=f"wave seeds per evaluation entry (seed + {REPLICATE_STEP} r)")
    p.add_argument("--seed-set", choices=sorted(SEED_SETS), default="eval",
                   help="eval: wave seeds 1000·code + j (+100 r); final: the same + 20000, fresh seeds for the "
                        "final numbers (never used in tuning, training or selection)")
    p.add_argument("--discard", type=float, default=None, help="start-up window (s; default min(60, T/2))")
    p.add_argument("--name", default=None, help="report name (default: the policy's file stem)")
    p.add_argument("--out-dir", default=DEFAULT_OUT_DIR,
                   help=f"folder of the report folders (default: {DEFAULT_OUT_DIR} under the current directory; "
                        "the committed reports are docs/reports)")
    p.add_argument("--force", action="store_true", help="replace an existing report folder")
    p.add_argument("--html", action="store_true", help="also write report.html")
    p.add_argument("--no-plots", action="store_true")
    p.add_argument("--boot", type=int, default=2000, help="bootstrap resamples")
    p.add_argument("--tuned", default=None, help="tuned-baseline YAML (default agents/hyperparams/baselines.yml)")
    p.add_argument("--reuse", action="append", default=[], metavar="BASELINE=REPORT_DIR",
                   help="take a baseline's per-episode rows from an earlier report of the same episodes instead of "
                        "running it (e.g. clairvoyant=docs/reports/ars_WinchPayout-v0: its plans cost ~2 min per "
                        "episode); refused unless the controllers both runs share agree in every episode")
    args = p.parse_args(argv)
    if args.replicates < 1:
        p.error(f"--replicates must be ≥ 1 (got {args.replicates})")
    if args.boot < 1:
        p.error(f"--boot must be ≥ 1 (got {args.boot})")
    if args.discard is not None and not args.discard >= 0:
        p.error(f"--discard must be ≥ 0 (got {args.discard})")
    reuse = {}
    for item in args.reuse:
        name, sep, folder = item.partition("=")
        if not sep or not name or not folder:
            p.error(f"--reuse takes BASELINE=REPORT_DIR (got {item!r})")
        if not (Path(folder) / "summary.json").is_file() or not (Path(folder) / "metrics.csv").is_file():
            p.error(f"--reuse {name}: {folder} is not a report folder (no summary.json and metrics.csv)")
        reuse[name] = folder
    args.reuse = reuse
    if args.name is not None and (not args.name or args.name in (".", "..") or "/" in args.name
                                  or os.sep in args.name):
        p.error(f"--name must be a plain folder name (got {args.name!r})")
    return args


# ------------------------------------------------------------------------------------------ seed sets
def episode_seeds(base_seeds, seed_set: str = "eval", replicates: int = 1) -> list[int]:
    """The wave seeds of the episode list: every base seed (1000·code + j) + the set's offset +
    100 r for r < ``replicates`` (the order of :func:`agents.evaluation.eval_episodes`)."""
    off = SEED_SETS[seed_set]
    return [int(b) + off + REPLICATE_STEP * r for b in base_seeds for r in range(max(1, replicates))]


def reserved_seeds(base_seeds, seed_set: str = "eval") -> dict[str, set]:
    """Seeds the ``seed_set`` must not use: tuning, Hover design and training validation seeds of every
    base seed, and for ``final`` also every eval-set seed (any allowed number of replicates)."""
    out = {k: {int(b) + o for b in base_seeds} for k, o in RESERVED_OFFSETS.items()}
    if seed_set != "eval":
        out["eval set"] = set(episode_seeds(base_seeds, "eval", MAX_EVAL_REPLICATES))
    return out


def check_seed_set(all_base_seeds, chosen_base_seeds, seed_set: str, replicates: int) -> str | None:
    """An error message when the chosen episodes' seeds collide with reserved seeds (or repeat)."""
    seeds = episode_seeds(chosen_base_seeds, seed_set, replicates)
    if len(set(seeds)) != len(seeds):
        return (f"--replicates {replicates} repeats wave seeds across sea states (seed + {REPLICATE_STEP} r "
                f"reaches the next entry's seeds); use fewer replicates")
    for what, res in reserved_seeds(all_base_seeds, seed_set).items():
        clash = sorted(set(seeds) & res)
        if clash:
            return (f"--replicates {replicates} with --seed-set {seed_set} reaches the {what} seeds "
                    f"(e.g. {clash[0]}); at most {MAX_EVAL_REPLICATES} replicates of the eval set, or use "
                    f"--seed-set final")
    return None


@contextlib.contextmanager
def _seed_offset(offset: int):
    """Shift the wave seeds of :func:`agents.evaluation.eval_episodes` by ``offset`` for the duration
    (``run_evaluation`` builds its episode list with it and takes no offset)."""
    import agents.evaluation as ev
    orig = ev.eval_episodes
    if not offset:
        yield
        return

    def shifted(env, replicates=1, indices=None):
        return [(g, lab, sea, int(seed) + offset) for g, lab, sea, seed in orig(env, replicates, indices)]

    ev.eval_episodes = shifted
    try:
        yield
    finally:
        ev.eval_episodes = orig


def seed_set_sentence(seed_set: str, replicates: int) -> str:
    off = SEED_SETS[seed_set]
    rep = f" + {REPLICATE_STEP} r (r < {replicates})" if replicates > 1 else ""
    if seed_set == "final":
        return (f"**final** set — 1000·code + j + {off}{rep}: fresh wave seeds for final numbers, never used in "
                f"baseline tuning (+500), the Hover design (+900), training validation (+700) or the eval set "
                f"(+0 … +400).")
    return (f"**eval** set — 1000·code + j{rep}: the evaluation list the policies were selected on (use "
            f"`--seed-set final` for final numbers).")


# ------------------------------------------------------------------------------------------ policy files
#: ARS policy files (.npz) by the ``env_id`` and ``algo`` of their metadata: the module that loads them
NPZ_LOADERS = {("towenv/WinchPayout-v0", "ars"): ("agents.ars", "load_ars_policy"),
               ("towenv/CompensatorGains-v0", "ars_skyhook"): ("agents.ars_compensator", "load_policy")}


def load_policy_file(path, algo: str | None = None):
    """A policy from a file: an .npz is an ARS policy, loaded by the module its metadata's (env_id, algo) names
    (:data:`NPZ_LOADERS`; ValueError for an .npz that is none of them); anything else goes to
    :func:`agents.zoo.load_policy` (SB3 zip)."""
    import importlib
    import json

    import numpy as np
    path = Path(path)
    if path.suffix != ".npz":
        from agents.zoo import load_policy
        return load_policy(path, algo=algo)
    with np.load(path, allow_pickle=False) as z:
        meta = json.loads(str(z["meta"])) if "meta" in z else {}
    key = (meta.get("env_id"), meta.get("algo")) if isinstance(meta, dict) else (None, None)
    if key not in NPZ_LOADERS:
        known = "; ".join(f"env_id {e!r} + algo {a!r}" for e, a in NPZ_LOADERS)
        raise ValueError(f"unknown policy file: {path.name} has env_id {key[0]!r}, algo {key[1]!r} in its "
                         f"metadata (known .npz policies: {known})")
    mod, fn = NPZ_LOADERS[key]
    return getattr(importlib.import_module(mod), fn)(path)


# ------------------------------------------------------------------------------------------ main
def main(argv=None):
    args = parse_args(argv)
    from towenv.extras import RL_COMMAND_MODULES, require_extra
    require_extra("rl", "evaluate.py", RL_COMMAND_MODULES)
    import torch
    torch.set_num_threads(1)
    from agents.aggregate import across_seeds, seed_groups
    from agents.baselines import BASELINES, baseline_names, load_tuned
    from agents.common import env_kind
    from agents.evaluation import _PHYSICS_KEYS, ReuseError, make_eval_env, run_evaluation
    from agents.report import MIN_VERDICT_EPISODES, format_goal_value, verdict, write_report
    from agents.zoo import parse_env_kwargs

    trained = []
    env_id = args.env
    base_kwargs: dict = {}
    baselines = args.baselines
    for i, spec in enumerate([args.policy] + list(args.also)):
        if spec in BASELINES and i == 0:
            if env_id is None:
                kind = BASELINES[spec][0]
                env_id = "towenv/CompensatorGains-v0" if kind == "compensator" else "towenv/WinchPayout-v0"
            continue
        path = Path(spec)
        if not path.is_file():
            _fail(f"{spec!r} is neither a file nor a baseline name ({', '.join(BASELINES)})")
        try:
            pol = load_policy_file(path, algo=args.algo)
        except Exception as e:      # not a zip, unknown algorithm, unknown .npz, ...
            _fail(f"{spec}: cannot load the policy ({type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''})")
        meta = pol.meta
        eid = meta.get("env_id") or env_id
        if eid is None:
            _fail(f"{spec}: no environment id in the zip; pass --env")
        if env_id is None:
            env_id = eid
        elif eid != env_id:
            _fail(f"{spec} was trained on {eid}, not {env_id}")
        if i == 0:
            base_kwargs = {k: v for k, v in (meta.get("env_kwargs") or {}).items() if k not in TRAINING_ONLY}
        meta = dict(meta)
        meta["env_kwargs"] = {k: v for k, v in (meta.get("env_kwargs") or {}).items() if k not in TRAINING_ONLY}
        name = path.stem
        if any(n == name for n, *_ in trained):
            name = f"{name}_{i}"
        trained.append((name, pol, meta))
    if env_id is None:
        _fail(f"{args.policy}: give --env")
    try:
        base_kwargs.update(parse_env_kwargs(args.env_kwargs))
    except ValueError as e:
        _fail(str(e))

    # ---- the report folder: refuse an existing one before spending any time
    name = args.name or (Path(args.policy).stem if trained else f"baselines_{env_id.split('/')[-1]}")
    out = Path(args.out_dir) / name
    if out.exists() and not args.force:
        _fail(f"{out} exists; pass --force to replace it, or choose another --out-dir/--name")
    if out.exists() and not out.is_dir():
        _fail(f"{out} exists and is not a folder")

    # ---- inputs checked against the environment
    try:
        env = make_eval_env(env_id, base_kwargs)
    except Exception as e:      # unknown id, unknown keyword, bad value
        _fail(f"cannot make {env_id} with {base_kwargs}: {type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}")
    base = [int(s) for _, s in env.unwrapped.eval_sea_states()]
    kind = env_kind(env.unwrapped)
    env.close()
    idx = list(range(len(base))) if args.episodes is None else list(args.episodes)
    bad = [i for i in idx if not 0 <= i < len(base)]
    if bad or not idx:
        _fail(f"--episodes: indices must be in 0..{len(base) - 1} (got {args.episodes})")
    if baselines is not None:
        unknown = [b for b in baselines if b not in baseline_names(kind)]
        if unknown:
            _fail(f"--baselines: {', '.join(unknown)} not baselines of {env_id} ({', '.join(baseline_names(kind))})")
    for n, _pol, meta in trained:
        kw = dict(meta.get("env_kwargs") or {})
        kw.update(base_kwargs)
        for k in _PHYSICS_KEYS:
            if kw.get(k) != base_kwargs.get(k):
                _fail(f"{n}: environment keyword {k!r} = {kw.get(k)!r} differs from the evaluation's "
                      f"({base_kwargs.get(k)!r}); pass it with --env-kwargs")
    msg = check_seed_set(base, [base[i] for i in idx], args.seed_set, args.replicates)
    if msg:
        _fail(msg)
    try:
        tuned = load_tuned(args.tuned) if args.tuned else None
    except Exception as e:
        _fail(f"--tuned {args.tuned}: {type(e).__name__}: {e}")

    # ---- run
    offset = SEED_SETS[args.seed_set]
    kw = dict(baselines=baselines, env_kwargs=base_kwargs, replicates=args.replicates, indices=idx,
              discard=args.discard, n_boot=args.boot, tuned=tuned)
    if args.reuse:
        kw["reuse"] = args.reuse
        bad = [n for n in args.reuse if n not in (baselines if baselines is not None else baseline_names(kind))]
        if bad:
            _fail(f"--reuse: {', '.join(bad)} not among this run's baselines")
    try:
        if "seed_offset" in inspect.signature(run_evaluation).parameters:
            res = run_evaluation(env_id, trained, seed_offset=offset, **kw)
        else:
            with _seed_offset(offset):
                res = run_evaluation(env_id, trained, **kw)
    except ReuseError as e:
        _fail(str(e))
    expect = episode_seeds([base[i] for i in idx], args.seed_set, args.replicates)
    got = [int(e[3]) for e in res.episodes]
    if got != expect:       # the episode list is not what this script promises: do not write a report
        raise RuntimeError(f"episode wave seeds {got[:4]}... differ from the {args.seed_set} set {expect[:4]}...")

    # ---- across training seeds
    groups = []
    for fam, members in seed_groups([n for n, *_ in trained]).items():
        if len(members) >= 2:
            groups.append(across_seeds(res, members, fam, reps=args.boot))

    cmd = "python scripts/evaluate.py " + " ".join(shlex.quote(a) for a in (argv if argv is not None else sys.argv[1:]))
    title = f"Evaluation report: {name}"
    md = write_report(res, out, title, command=cmd, html_too=args.html, plots=not args.no_plots,
                      seed_set=seed_set_sentence(args.seed_set, args.replicates), across_seeds=groups)
    print(f"[evaluate] wrote {md} ({len(res.episodes)} episodes, {args.seed_set} seed set)", flush=True)
    n_ep = len(res.episodes)
    if res.goals and n_ep < MIN_VERDICT_EPISODES:
        print(f"[evaluate] no verdict: {n_ep} episodes < {MIN_VERDICT_EPISODES} (e.g. --replicates 2 on the 12 "
              f"entries); figures for information only", flush=True)
    for g in res.goals:
        val = format_goal_value(g)
        print(f"[evaluate] {g['policy']}: {g['criterion']}: {val} -> {verdict(g, n_ep)}", flush=True)
    for gr in groups:
        note = "" if gr["n_seeds"] >= 3 else " (issue 14 asks for at least 3)"
        print(f"[evaluate] across training seeds: {gr['family']}: {gr['n_seeds']} seeds{note}, "
              f"{gr['n_tasks']} episodes", flush=True)
        for k, d in gr["metrics"].items():
            p, lo, hi = d["iqm"]
            sc = 100.0 if d["pct"] else 1.0
            unit = " %" if d["pct"] else ""
            print(f"[evaluate]   {d['label'].replace('`', '')}: IQM {sc * p:.3g}{unit} [{sc * lo:.3g}, {sc * hi:.3g}]", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
