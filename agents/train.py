"""Train an SB3 agent (PPO or SAC, also TD3/A2C/DDPG) on a towenv environment.

Hyperparameters come from an rl-zoo style YAML (``agents/hyperparams/<algo>.yml``, top-level key = the
environment id). Writes, under ``--log-dir/<run name>/``:

* ``tb/``                       TensorBoard logs (``tensorboard --logdir runs``);
* ``checkpoints/``              model + VecNormalize statistics (+ replay buffer for off-policy
                                algorithms) every ``--save-freq`` transitions; ``--resume`` continues
                                from the newest one (same run name) up to ``n_timesteps``;
* ``best/best_model.zip``       best model on a separate validation set (EvalCallback; wave seeds that
                                are neither the evaluation seeds nor random training seeds);
* ``final.zip``                 self-contained policy zip (model + ``vecnormalize.pkl`` + ``towenv.json``),
                                also copied to ``--export`` if given (e.g. ``agents/trained/...zip``);
* ``run_info.json``             steps, wall-clock time, arguments.

Examples::

    python scripts/train.py --algo ppo --env towenv/WinchPayout-v0 --seed 0
    python scripts/train.py --algo sac --env towenv/CompensatorGains-v0 --n-timesteps 200000 \\
        --max-minutes 30 --export agents/trained/sac_CompensatorGains-v0.zip
    python scripts/train.py --algo ppo --env towenv/WinchPayout-v0 --resume      # continue the run
    python scripts/train.py --algo ppo --env towenv/WinchPayout-v0 --n-timesteps 4096 \\
        --env-kwargs episode_seconds:30 --eval-freq 0                              # smoke run (~10 s)

How long: the YAML recipes (agents/hyperparams/ppo.yml) train 6 M steps on WinchPayout and 4 M on
CompensatorGains, ~35 and ~25-30 min per seed on one core of the project's 2-core machine (2300-3400
env steps/s with 16 batched copies; docs/agents.md). PPO collects n_steps x n_envs steps per update
(16 x 256 = 4096 for CompensatorGains, 16 x 1024 for WinchPayout) and rounds --n-timesteps up to a
multiple of it (the script says so).
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import time
from pathlib import Path

# one thread per process for the command line (set before numpy/numba load their pools). Imported into a
# process that has already loaded numba (a test, a notebook), NUMBA_NUM_THREADS is left alone: numba re-reads
# its configuration at every compilation and refuses a thread count that differs from the pool it launched
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    if _v != "NUMBA_NUM_THREADS" or "numba" not in sys.modules:
        os.environ.setdefault(_v, "1")


if __name__ == "__main__":          # before the SB3 callback classes below are defined
    from towenv.extras import RL_COMMAND_MODULES, require_extra
    require_extra("rl", "train.py", RL_COMMAND_MODULES)


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("--algo", default="ppo", choices=["ppo", "sac", "td3", "a2c", "ddpg"])
    p.add_argument("--env", default="towenv/WinchPayout-v0", help="environment id")
    p.add_argument("--conf", "--conf-file", dest="conf", default=None,
                   help="hyperparameter YAML (default agents/hyperparams/<algo>.yml)")
    p.add_argument("--n-timesteps", "-n", type=int, default=None, help="override n_timesteps of the YAML")
    p.add_argument("--n-envs", type=int, default=None, help="override n_envs of the YAML")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--env-kwargs", nargs="*", default=None, metavar="KEY:VALUE",
                   help="environment keywords (Python literals), override the YAML's env_kwargs")
    p.add_argument("--hyperparams", "-params", nargs="*", default=None, metavar="KEY:VALUE",
                   help="override algorithm hyperparameters of the YAML (Python literals; lin_<x> schedules)")
    p.add_argument("--log-dir", "-f", default="runs", help="root folder of the runs (default runs/)")
    p.add_argument("--name", default=None, help="run name (default <algo>_<env>_s<seed>)")
    p.add_argument("--save-freq", type=int, default=50_000, help="checkpoint every N transitions (0: never)")
    p.add_argument("--keep-checkpoints", type=int, default=2, help="checkpoints kept (oldest removed)")
    p.add_argument("--eval-freq", type=int, default=50_000,
                   help="validation every N transitions (0: no EvalCallback)")
    p.add_argument("--eval-episodes", type=int, default=6, help="validation episodes per evaluation")
    p.add_argument("--eval-seconds", type=float, default=None,
                   help="validation episode length (s; default: the training episode length)")
    p.add_argument("--resume", action="store_true", help="continue from the newest checkpoint of this run")
    p.add_argument("--max-minutes", type=float, default=None, help="stop (and save) after this wall-clock time")
    p.add_argument("--progress-bar", dest="progress_bar", action="store_true", default=True)
    p.add_argument("--no-progress-bar", dest="progress_bar", action="store_false")
    p.add_argument("--export", default=None, help="copy the exported policy zip here")
    p.add_argument("--export-which", choices=["best", "last"], default="best",
                   help="export the validation-best model (default, if any) or the last one")
    p.add_argument("--vec-env", choices=["batched", "dummy", "subproc"], default="batched",
                   help="batched (default): all copies in one compiled call (towenv.envs.sb3.TowSB3VecEnv); "
                        "dummy/subproc: SB3's Python loop / processes over single environments")
    p.add_argument("--parallel", action="store_true",
                   help="batched env: step the copies with numba.prange on all cores (NUMBA_NUM_THREADS)")
    p.add_argument("--threads", type=int, default=1, help="torch threads (1 is fastest for small MLPs on CPU)")
    p.add_argument("--device", default="cpu")
    p.add_argument("--verbose", type=int, default=0)
    return p.parse_args(argv)


def validation_seas(env_id: str, env_kwargs: dict, n: int):
    """Validation sea states: the evaluation (Hs, Tp, heading) presets with wave seeds + 700 (neither the
    evaluation seeds nor the ones the baselines were tuned on, + 500)."""
    import gymnasium as gym
    import towenv.envs  # noqa: F401
    e = gym.make(env_id, **env_kwargs)
    ev = e.unwrapped.eval_sea_states()
    e.close()
    order = list(range(len(ev)))
    # spread over codes: 0, 4, 8, 1, 5, 9, ...
    per = max(1, len(ev) // 3)
    order = [i + j * per for i in range(per) for j in range(len(ev) // per)]
    return [(ev[i][0], ev[i][1] + 700) for i in order[:max(1, n)]]


def resolve_tuned_tables(wrappers):
    """Replace ``table: tuned`` in a residual wrapper by the tuned table itself (from
    agents/hyperparams/baselines.yml at training time), so the policy zip's metadata carries the exact base
    controller it was trained on, whatever later retuning does to the YAML."""
    from agents.baselines import load_tuned
    from agents.zoo import _wrapper_list
    out = []
    for name, kw in _wrapper_list(wrappers):
        kw = dict(kw)
        if kw.get("table") == "tuned":
            tab = load_tuned().get(kw.get("base", "along_cable"))
            if not tab:
                raise SystemExit(f"train.py: no tuned {kw.get('base')!r} table in agents/hyperparams/baselines.yml "
                                 f"(run python -m agents.tuning)")
            kw["table"] = {k: {n: v for n, v in e.items() if not isinstance(v, str)} for k, e in tab.items()}
        out.append({name: kw})
    return out or None


def batched_venv(env_id: str, n_envs: int, env_kwargs: dict, wrappers, seed: int, parallel: bool = False):
    """The batched SB3 VecEnv (one compiled call steps all copies; copy i seeded seed + i) with a VecMonitor and
    the YAML's wrappers: ``agents.wrappers.ResidualAction`` becomes its batched twin
    :class:`agents.wrappers.ResidualVecAction` (same keywords); other wrappers need ``--vec-env dummy``."""
    from stable_baselines3.common.vec_env import VecMonitor
    from agents.wrappers import GainScheduleVecAction, ResidualVecAction
    from agents.zoo import _wrapper_list
    from towenv.envs.sb3 import TowSB3VecEnv
    venv = VecMonitor(TowSB3VecEnv(env_id, n_envs, seed=seed, parallel=parallel, **env_kwargs))
    for name, kw in _wrapper_list(wrappers):
        if name.endswith("ResidualAction"):
            venv = ResidualVecAction(venv, **kw)
        elif name.endswith("GainScheduleAction"):
            venv = GainScheduleVecAction(venv, **kw)
        else:
            raise SystemExit(f"train.py: wrapper {name} has no batched form; use --vec-env dummy")
    return venv


def rollout_steps(model) -> int:
    """Steps an SB3 model collects per update: ``n_steps × n_envs`` on-policy (PPO, A2C), ``n_envs``
    off-policy; ``learn`` rounds the total up to a multiple of it."""
    n_envs = int(getattr(model, "n_envs", 1) or 1)
    return int(getattr(model, "n_steps", 1)) * n_envs


def main(argv=None):
    args = parse_args(argv)       # (SB3 is imported with this module: the extras check is at the top)
    import numpy as np
    import torch
    torch.set_num_threads(max(1, args.threads))

    from stable_baselines3.common.callbacks import (BaseCallback, CallbackList, EvalCallback)
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecNormalize

    from agents.common import short_env_name
    from agents.zoo import (ALGOS, HYPERPARAMS_DIR, load_hyperparams, make_env_fn, parse_env_kwargs,
                            save_policy_zip)

    conf = Path(args.conf) if args.conf else HYPERPARAMS_DIR / f"{args.algo}.yml"
    hp = load_hyperparams(conf, args.env)
    n_envs = args.n_envs or hp["n_envs"]
    n_timesteps = args.n_timesteps or hp["n_timesteps"]
    env_kwargs = dict(hp["env_kwargs"])
    env_kwargs.update(parse_env_kwargs(args.env_kwargs))
    wrappers = resolve_tuned_tables(hp["env_wrapper"])
    for k, v in parse_env_kwargs(args.hyperparams).items():
        if isinstance(v, str) and v.startswith("lin_"):
            from agents.zoo import linear_schedule
            v = linear_schedule(float(v[4:]))
        hp["algo_kwargs"][k] = v
        hp["raw"][k] = v if not callable(v) else f"lin_{v.initial:g}"
    name = args.name or f"{args.algo}_{short_env_name(args.env)}_s{args.seed}"
    run = Path(args.log_dir) / name
    ckpt_dir = run / "checkpoints"
    run.mkdir(parents=True, exist_ok=True)
    ckpt_dir.mkdir(exist_ok=True)

    if args.vec_env == "batched":
        venv = batched_venv(args.env, n_envs, env_kwargs, wrappers, args.seed, args.parallel)
    else:
        fns = [make_env_fn(args.env, env_kwargs, wrappers, seed=args.seed + 1000 * i) for i in range(n_envs)]
        if args.vec_env == "subproc" and n_envs > 1:
            venv = SubprocVecEnv(fns, start_method="forkserver")
        else:
            venv = DummyVecEnv(fns)
        venv.seed(args.seed)
    norm = hp["normalize"]
    if norm is not None:
        venv = VecNormalize(venv, gamma=hp["algo_kwargs"].get("gamma", 0.99), **norm)

    algo_cls = ALGOS[args.algo]
    try:
        import tensorboard  # noqa: F401
        tb_dir = str(run / "tb")
    except ImportError:
        tb_dir = None
        print("[train] tensorboard is not installed: no TensorBoard logs (pip install tensorboard)", flush=True)
    start_steps = 0
    latest = _latest_checkpoint(ckpt_dir) if args.resume else None
    if args.resume and latest is None:
        print(f"[train] --resume: no checkpoint in {ckpt_dir}; starting a new run", flush=True)
    if latest is not None:
        steps, zpath = latest
        print(f"[train] resuming from {zpath} ({steps} steps)", flush=True)
        vn = ckpt_dir / f"ckpt_{steps}_vecnormalize.pkl"
        if norm is not None and vn.exists():
            venv = VecNormalize.load(str(vn), venv.venv)
        model = algo_cls.load(zpath, env=venv, device=args.device, tensorboard_log=tb_dir)
        rb = ckpt_dir / f"ckpt_{steps}_replay_buffer.pkl"
        if hasattr(model, "load_replay_buffer") and rb.exists():
            model.load_replay_buffer(rb)
        start_steps = model.num_timesteps
    else:
        model = algo_cls(hp["policy"], venv, seed=args.seed, device=args.device, verbose=args.verbose,
                         tensorboard_log=tb_dir, **hp["algo_kwargs"])

    callbacks: list[BaseCallback] = []
    if args.save_freq > 0:
        callbacks.append(_Checkpoint(ckpt_dir, max(1, args.save_freq // n_envs), args.keep_checkpoints))
    if args.eval_freq > 0:
        from towenv.envs.pieces import FixedSeas
        ekw = dict(env_kwargs)
        if args.eval_seconds:
            ekw["episode_seconds"] = args.eval_seconds
        ekw["sea_generator"] = FixedSeas(validation_seas(args.env, ekw, args.eval_episodes))
        if args.vec_env == "batched":            # same wrapper chain as the training env (VecNormalize sync)
            eval_env = batched_venv(args.env, 1, ekw, wrappers, args.seed + 12345)
        else:
            eval_env = DummyVecEnv([make_env_fn(args.env, ekw, wrappers, seed=args.seed + 12345)])
        if norm is not None:
            eval_env = VecNormalize(eval_env, training=False, norm_obs=norm.get("norm_obs", True), norm_reward=False)
        callbacks.append(EvalCallback(eval_env, best_model_save_path=str(run / "best"), log_path=str(run / "eval"),
                                      eval_freq=max(1, args.eval_freq // n_envs),
                                      n_eval_episodes=args.eval_episodes, deterministic=True, verbose=args.verbose))
    if args.progress_bar:
        callbacks.append(_TqdmBar(n_timesteps, start_steps))
    if args.max_minutes:
        callbacks.append(_WallClock(args.max_minutes * 60.0))

    remaining = max(0, n_timesteps - start_steps)
    chunk = rollout_steps(model)
    if remaining % chunk:
        planned = -(-remaining // chunk) * chunk
        print(f"[train] note: {args.algo} collects {chunk} steps at a time ("
              + (f"n_steps {model.n_steps} × n_envs {model.n_envs}" if hasattr(model, "n_steps") else f"n_envs {model.n_envs}")
              + f"), so {remaining} steps become {planned}", flush=True)
    t0 = time.time()
    print(f"[train] {args.algo} on {args.env}: {remaining} steps to go (of {n_timesteps}), n_envs={n_envs}, "
          f"run dir {run}", flush=True)
    interrupted = False
    try:
        if remaining > 0:
            model.learn(total_timesteps=remaining, callback=CallbackList(callbacks), tb_log_name="tb",
                        reset_num_timesteps=latest is None, progress_bar=False)
    except KeyboardInterrupt:
        interrupted = True
        print("[train] interrupted: saving", flush=True)
    wall = time.time() - t0
    # final checkpoint (so that --resume continues exactly here)
    _save_checkpoint(model, ckpt_dir, args.keep_checkpoints)

    meta = {"algo": args.algo, "env_id": args.env, "env_kwargs": env_kwargs, "env_wrapper": wrappers,
            "seed": args.seed, "n_envs": n_envs, "num_timesteps": int(model.num_timesteps),
            "n_timesteps_target": int(n_timesteps), "wall_seconds_this_session": round(wall, 1),
            "hyperparams_file": str(conf), "hyperparams": hp["raw"], "run_dir": str(run),
            "versions": _versions()}
    vecnorm = model.get_vec_normalize_env()
    last = save_policy_zip(model, run / "final.zip", meta | {"selected": "last"}, vecnorm)
    chosen = last
    best = run / "best" / "best_model.zip"
    if args.export_which == "best" and best.exists() and args.eval_freq > 0:
        best_model = algo_cls.load(best, device=args.device)
        evals = _read_evals(run / "eval" / "evaluations.npz")
        chosen = save_policy_zip(best_model, run / "best_policy.zip",
                                 meta | {"selected": "best on validation seeds (EvalCallback)", "validation": evals},
                                 vecnorm)
    if args.export:
        Path(args.export).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(chosen, args.export)
        print(f"[train] exported {chosen} -> {args.export}", flush=True)
    info = {"args": vars(args), "num_timesteps": int(model.num_timesteps), "wall_seconds": round(wall, 1),
            "steps_per_second": round((model.num_timesteps - start_steps) / max(wall, 1e-9), 1),
            "interrupted": interrupted, "final": str(last), "exported": str(chosen)}
    prev = run / "run_info.json"
    if prev.exists():
        try:
            old = json.loads(prev.read_text())
            info["wall_seconds_total"] = round(old.get("wall_seconds_total", old.get("wall_seconds", 0)) + wall, 1)
        except (ValueError, OSError):
            pass
    info.setdefault("wall_seconds_total", round(wall, 1))
    prev.write_text(json.dumps(info, indent=2, default=str))
    print(f"[train] done: {model.num_timesteps} steps, {wall:.0f} s this session -> {chosen}", flush=True)
    np.seterr(all="ignore")
    return 0


# ---------------------------------------------------------------------------------------------------
def _versions():
    import gymnasium
    import stable_baselines3
    import torch
    import towenv
    return {"towenv": towenv.__version__, "gymnasium": gymnasium.__version__, "sb3": stable_baselines3.__version__,
            "torch": torch.__version__}


def _read_evals(path):
    import numpy as np
    if not Path(path).exists():
        return None
    d = np.load(path)
    r = d["results"].mean(axis=1)
    i = int(np.argmax(r))
    return {"best_timestep": int(d["timesteps"][i]), "best_mean_reward": float(r[i]),
            "timesteps": [int(x) for x in d["timesteps"]], "mean_rewards": [round(float(x), 3) for x in r]}


def _latest_checkpoint(ckpt_dir: Path):
    found = []
    for p in ckpt_dir.glob("ckpt_*.zip"):
        try:
            found.append((int(p.stem.split("_")[1]), p))
        except (IndexError, ValueError):
            continue
    return max(found) if found else None


def _save_checkpoint(model, ckpt_dir: Path, keep: int):
    steps = int(model.num_timesteps)
    model.save(ckpt_dir / f"ckpt_{steps}.zip")
    vn = model.get_vec_normalize_env()
    if vn is not None:
        vn.save(str(ckpt_dir / f"ckpt_{steps}_vecnormalize.pkl"))
    if hasattr(model, "save_replay_buffer") and getattr(model, "replay_buffer", None) is not None:
        model.save_replay_buffer(ckpt_dir / f"ckpt_{steps}_replay_buffer.pkl")
    ck = sorted((int(p.stem.split("_")[1]), p) for p in ckpt_dir.glob("ckpt_*.zip"))
    for s, _ in ck[:-keep] if keep > 0 else []:
        for f in ckpt_dir.glob(f"ckpt_{s}*"):
            f.unlink()


def _callbacks_base():
    from stable_baselines3.common.callbacks import BaseCallback
    return BaseCallback


class _Checkpoint(_callbacks_base()):
    def __init__(self, ckpt_dir, every_calls, keep):
        super().__init__()
        self.ckpt_dir, self.every, self.keep = ckpt_dir, every_calls, keep

    def _on_step(self):
        if self.n_calls % self.every == 0:
            _save_checkpoint(self.model, self.ckpt_dir, self.keep)
        return True


class _TqdmBar(_callbacks_base()):
    """Progress bar with tqdm only (SB3's own bar needs ``rich``, which is not a dependency)."""

    def __init__(self, total, start):
        super().__init__()
        self.total, self.start = total, start
        self.bar = None

    def _on_training_start(self):
        from tqdm import tqdm
        self.bar = tqdm(total=self.total, initial=self.start, unit="step", dynamic_ncols=True, mininterval=2.0,
                        file=sys.stderr)

    def _on_step(self):
        self.bar.n = int(self.model.num_timesteps)
        self.bar.update(0)
        return True

    def _on_training_end(self):
        if self.bar is not None:
            self.bar.n = int(self.model.num_timesteps)
            self.bar.close()


class _WallClock(_callbacks_base()):
    def __init__(self, seconds):
        super().__init__()
        self.seconds = seconds
        self.t0 = None

    def _on_training_start(self):
        self.t0 = time.time()

    def _on_step(self):
        if time.time() - self.t0 > self.seconds:
            print(f"\n[train] wall-clock limit ({self.seconds / 60:.1f} min) reached", flush=True)
            return False
        return True


if __name__ == "__main__":
    sys.exit(main())
