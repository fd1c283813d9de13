"""The CompensatorGains one-hour recipe in one command (issue 14; docs/agents.md "The headline's stages within the
hour"): from the committed ARS start, the headline ``gnsfo``'s four Gauss–Newton stages, each with the shared warm-up
of the Jacobian episodes, one after another on both cores; the last stage's budget is what is left of the hour:

    python scripts/train_compensator_hour.py --seed 2     # -> runs/gnw/gnw{,s,sf,sfo,t}_CompensatorGains-v0_s2.npz

    stage 1  gnw     all weights of feature set h     6 iterations (cap 90 min)
    stage 2  gnws    + the skyhook-gated copy (hs)    4 iterations (cap 62 min)
    stage 3  gnwsf   + the fish-gated copy (hsf)      8 iterations (cap 22 min)
    stage 4  gnwsfo  + the outward-gated copy (hsfo)  8 iterations, budget min(12, HOUR - start - elapsed) min
    then     gnwt    the mean of the last ceil(n/2) of stages 3-4's n iterates (Θ after each step; in hsfo;
                     stage 3's alone if the hour left stage 4 less than a minute, on a slow host)

HOUR is 57.5 min, start the ARS start's own training time (9.3 min for ``arsp`` seed 0, read from its file; the declared chains used 9.4) and
elapsed the wall of stages 1-3. Run it alone on the machine: the committed seeds took 57.0-57.4 min of wall with the
ARS start (``python scripts/training_cost.py agents/trained/gnwsfo_CompensatorGains-v0_s0.npz``); the average adds
about a second and is the chain's product (``gnwt``; docs/agents.md "A steadier end": on the evaluation set it beat
the last iterate, 17.8 against 16.5 % seed mean). ``--dry-run`` prints the stages' commands
(``scripts/train_gn_compensator.py``, ``scripts/average_compensator.py``) without running them. One BLAS thread unless
OPENBLAS_NUM_THREADS or OMP_NUM_THREADS is set, as the committed files were trained.
"""
import os

BLAS_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")
if not any(v in os.environ for v in BLAS_VARS):
    for _var in BLAS_VARS:
        os.environ[_var] = "1"

import argparse  # noqa: E402  (after the thread setting: OpenBLAS reads it when numpy loads it)
import math  # noqa: E402
import shlex  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

HOUR_MINUTES = 57.5      # the chain's wall including the ARS start's training, with ~2.5 min of process start-ups
LAST_STAGE_CAP = 12.0    # minutes: stage 4's budget never exceeds this
MIN_LAST_STAGE = 1.0     # minutes: below this the hour is spent and stage 4 is not started
COMMON = ["--replicates", "2", "--ridges", "0.01", "0.1", "1", "10", "100", "--parallel", "--shared-warmup"]
AVERAGED_STAGES = (2, 3)  # the stages (0-based) whose iterates the tail average takes: fish-gated and outward
AVERAGE_FAMILY = "gnwt"
# (family, iterations, minutes cap or None for the hour's remainder, feature set or None, moved weights or None)
STAGES = (("gnw", 6, 90.0, None, None),
          ("gnws", 4, 62.0, "hs", "gated"),
          ("gnwsf", 8, 22.0, "hsf", "fish"),
          ("gnwsfo", 8, None, "hsfo", "outward"))
DEFAULT_START = Path("agents/trained/arsp_CompensatorGains-v0_s0.npz")


def policy_file(out_dir: Path, family: str, seed: int) -> Path:
    """The policy file of ``family`` and ``seed`` in ``out_dir`` (the committed files' naming)."""
    return out_dir / f"{family}_CompensatorGains-v0_s{seed}.npz"


def default_start() -> Path:
    """The committed ARS start: ``agents/trained/…`` of the working directory (a clone), else the installed package's."""
    if DEFAULT_START.exists():
        return DEFAULT_START
    import agents
    return Path(agents.__file__).parent / "trained" / DEFAULT_START.name


def stage_args(seed: int, stage: int, minutes: float, start: Path, out_dir: Path) -> list[str]:
    """The ``train_gn_compensator.py`` arguments of stage ``stage`` (0-based) of seed ``seed``."""
    family, iterations, _, features, free = STAGES[stage]
    init = start if stage == 0 else policy_file(out_dir, STAGES[stage - 1][0], seed)
    args = ["--seed", str(seed), "--iterations", str(iterations), "--minutes", f"{minutes:g}"] + COMMON
    if features:
        args += ["--features", features, "--free", free]
    if stage in AVERAGED_STAGES:
        args += ["--save-iterates"]
    return args + ["--init", str(init), "--export", str(policy_file(out_dir, family, seed))]


def tail_count(n: int) -> int:
    """How many of the last iterates the average takes: ceil(n / 2) of ``n``."""
    return math.ceil(n / 2)


def iterate_files(seed: int, out_dir: Path, stages=AVERAGED_STAGES) -> list[Path]:
    """The iterate files of the averaged ``stages`` in step order, named from each stage file's own iteration count
    (so files left by an earlier run in ``out_dir`` are not taken)."""
    from agents import ars_compensator as arc
    from agents.gn_compensator import iterate_stem
    files = []
    for k in stages:
        stage = policy_file(out_dir, STAGES[k][0], seed)
        meta = arc.load_policy(stage).meta
        first, n = int(meta["first_iteration"]), int(meta["iterations"])
        files += [stage.with_name(iterate_stem(stage.stem, i) + ".npz") for i in range(first, first + n)]
    return files


def average_args(seed: int, out_dir: Path, stages=AVERAGED_STAGES) -> list[str]:
    """``scripts/average_compensator.py``'s arguments for the chain's tail average (in stage 4's feature set) over the
    iterates of ``stages`` (stage 3 alone when the hour left no time for stage 4)."""
    files = iterate_files(seed, out_dir, stages)
    return _average_options(seed, out_dir) + [str(f) for f in files[-tail_count(len(files)):]]


def _average_options(seed: int, out_dir: Path) -> list[str]:
    """The tail average's options before its member files (``--dry-run`` prints them without the members, which the
    stage files name only once they exist)."""
    return ["--seed", str(seed), "--features", STAGES[-1][3],
            "--export", str(policy_file(out_dir, AVERAGE_FAMILY, seed))]


def _script(name: str):
    """A module of this folder (scripts/ is no package)."""
    import importlib.util
    spec = importlib.util.spec_from_file_location(name, Path(__file__).resolve().parent / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def last_budget(start_minutes: float, elapsed_minutes: float, hour: float = HOUR_MINUTES) -> float:
    """Stage 4's budget in minutes: min(12, hour - start - elapsed), rounded to 0.01 min (may be <= 0)."""
    return round(min(LAST_STAGE_CAP, hour - start_minutes - elapsed_minutes), 2)


def start_minutes(start: Path) -> float:
    """The training minutes of the start file's whole ``--init`` chain (scripts/training_cost.py's own costs)."""
    return sum(r[1] for r in _script("training_cost").chain(start)) / 60.0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="The CompensatorGains one-hour recipe: four Gauss-Newton stages with "
                                             "the shared warm-up from the committed ARS start (docs/agents.md \"The "
                                             "headline's stages within the hour\").")
    ap.add_argument("--seed", type=int, default=0, help="training seed of every stage (default 0)")
    ap.add_argument("--start", type=Path, default=None,
                    help=f"the ARS start every seed continues (default {DEFAULT_START})")
    ap.add_argument("--out-dir", type=Path, default=Path("runs/gnw"), help="where the four stage files go "
                                                                            "(default runs/gnw)")
    ap.add_argument("--hour", type=float, default=HOUR_MINUTES,
                    help=f"minutes the chain may take with the start's training (default {HOUR_MINUTES:g}); stage 4 "
                         f"gets what stages 1-3 leave, at most {LAST_STAGE_CAP:g}")
    ap.add_argument("--dry-run", action="store_true", help="print the four stages' commands and exit (stage 4's "
                                                          "budget as if stages 1-3 took no time)")
    a = ap.parse_args(argv)
    a.start = a.start or default_start()
    if a.seed < 0:
        ap.error(f"--seed must be >= 0 (got {a.seed})")
    if not (math.isfinite(a.hour) and a.hour > 0):
        ap.error(f"--hour must be a positive number of minutes (got {a.hour})")
    try:
        spent = start_minutes(a.start)
    except (OSError, ValueError) as e:
        ap.error(f"--start: {e}")
    if a.hour - spent < MIN_LAST_STAGE:
        ap.error(f"--hour must leave time after the start's {spent:.1f} min of training (got {a.hour:g} min)")

    def minutes_of(stage, elapsed):
        cap = STAGES[stage][2]
        return cap if cap is not None else last_budget(spent, elapsed, a.hour)

    if a.dry_run:
        for k in range(len(STAGES)):
            args = stage_args(a.seed, k, minutes_of(k, 0.0), a.start, a.out_dir)
            print(shlex.join([sys.executable, "scripts/train_gn_compensator.py"] + args))
        print(shlex.join([sys.executable, "scripts/average_compensator.py"] + _average_options(a.seed, a.out_dir))
              + " <the last ceil(n/2) of the n iterate files of stages 3-4>")
        return 0
    from agents.gn_compensator import main as train_stage
    t0 = time.monotonic()
    print(f"[hour] seed {a.seed}: the start {a.start} took {spent:.1f} min; the chain has {a.hour:g} min", flush=True)
    averaged = AVERAGED_STAGES
    for k, (family, *_rest) in enumerate(STAGES):
        elapsed = (time.monotonic() - t0) / 60.0
        minutes = minutes_of(k, elapsed)
        if minutes < MIN_LAST_STAGE:
            averaged = tuple(j for j in AVERAGED_STAGES if j < k)
            print(f"[hour] the hour is spent after {elapsed:.1f} min of stages (budget {minutes:.2f} min left): "
                  f"{family} not started; the tail average takes {STAGES[k - 1][0]}'s iterates alone", flush=True)
            break
        print(f"[hour] stage {k + 1}/{len(STAGES)} {family}: {minutes:g} min cap, {elapsed:.1f} min elapsed",
              flush=True)
        rc = train_stage(stage_args(a.seed, k, minutes, a.start, a.out_dir))
        if rc:
            return rc
    rc = _script("average_compensator").main(average_args(a.seed, a.out_dir, averaged))
    if rc:
        return rc
    total = (time.monotonic() - t0) / 60.0
    print(f"[hour] done: {total:.1f} min of stages + {spent:.1f} min of start = {total + spent:.1f} min "
          f"(python scripts/training_cost.py {policy_file(a.out_dir, AVERAGE_FAMILY, a.seed)})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
