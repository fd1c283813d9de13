"""Benchmark of the Gymnasium environments (towenv.envs): steps/s, reset time, batched vector-env throughput.

One process. For each environment id at the default 10 Hz control / 0.05 s physics step (2 physics sub-steps
per control step), random actions drawn in advance, evaluation sea 4 (coastal SS4, head seas, fixed seed):

* single env steps/s, unwrapped and through ``gym.make`` (Gymnasium's checker/order wrappers) — median of
  ``--repeats`` runs of ``--steps`` steps, by process CPU time (min–max and the wall-clock median too);
* the compiled step alone: the batch kernel for one copy with a fixed command, one control step per call, no
  Python around it but the stepper's; the physics alone: the same kernel advancing ``PHYSICS_CALL_STEPS`` control
  steps' worth of physics per call (per-call costs spread over them); the compiled step under the episode's
  commands (each step's random action mapped to commands as the env maps it, then the same call): a command that
  changes every control step costs the physics more Newton iterations (printed) than a fixed one, so the
  zero-overhead bound of the env step is the physics alone plus what the changing commands add (the difference of
  the two compiled-step runs: the same calls); and where a single env step's time goes (that physics, per-call
  compiled costs, Python around it — until 2026-12-07 the added physics was counted as Python);
* reset time: ``env.reset(seed=i)`` with a new random sea each time (sea synthesis, ``Simulator.reset``,
  the first tow-point block, the first observation) — median of 200;
* the batched vector env (``gym.make_vec(..., vectorization_mode="vector_entry_point")``, one numba call per
  step for all copies) for N = ``--sizes``: serial loop over copies (CPU time), and with ``parallel=True``
  (``prange`` over ``--threads`` numba threads; wall-clock time, since CPU time adds up the threads);
* for comparison, Python loops over N single envs: Gymnasium ``SyncVectorEnv`` (``vectorization_mode="sync"``)
  and SB3 ``DummyVecEnv`` (``make_vec_env``), and the SB3 adapter ``TowSB3VecEnv`` over the batched env;
* the yardstick of issue 15: Gymnasium's ``Pendulum-v1`` (unwrapped and through ``gym.make``, same steps and
  repeats, same run), and each towenv figure's cost per env-step as a multiple of a Pendulum step; and the same
  ratio from alternating runs of the two (paired: this host's speed changes for seconds at a time, so figures
  taken minutes apart may compare different machine states).

    python scripts/bench_env.py                                  # about two minutes
    python scripts/bench_env.py --steps 1000 --repeats 3 --sizes 1 8
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time

# BLAS/OpenMP single-threaded (OpenBLAS would spin a second thread in small matrix products); numba may use
# --threads threads, but only the prange variant uses more than one
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")
if "numba" not in sys.modules:      # loaded into a process with numba loaded (a test): leave its thread count alone
    os.environ.setdefault("NUMBA_NUM_THREADS", str(os.cpu_count() or 1))

import numpy as np  # noqa: E402


#: control steps' worth of physics per compiled call in the zero-overhead bound (``physics alone``): the per-call
#: costs (dispatch, measurement row, tow-point refills, Python) spread over this many control steps
PHYSICS_CALL_STEPS = 32


def _rate(fn, n, repeats):
    """(median, min, max) of n / CPU time over ``repeats`` runs, and the median of n / wall time."""
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        fn()
        cpu.append(n / (time.process_time() - c0))
        wall.append(n / (time.perf_counter() - w0))
    return statistics.median(cpu), min(cpu), max(cpu), statistics.median(wall)


def bench_single(env_id, steps, repeats):
    import gymnasium as gym
    made = gym.make(env_id)
    env = made.unwrapped
    acts = np.random.default_rng(0).uniform(-1, 1, (steps,) + env.action_space.shape).astype(np.float32)

    def run(e):
        def f():
            e.reset(seed=0, options={"eval_index": 4})
            for a in acts:
                e.step(a)
        return f

    run(env)()                                                     # warm-up (numba cache load, caches)
    out = {"unwrapped": _rate(run(env), steps, repeats), "gym.make": _rate(run(made), steps, repeats)}
    st = env._rows.stepper

    def kernel_only():
        env.reset(seed=0, options={"eval_index": 4})
        for _ in range(steps):
            st.step(env.substeps, env.ACT_KIND)
    out["kernel"] = _rate(kernel_only, steps, repeats)
    commanded = _commanded_kernel(env, acts)
    out["kernel_cmd"] = _rate(commanded, steps, repeats)
    per_call = PHYSICS_CALL_STEPS * env.substeps          # physics steps per call of the zero-overhead bound
    calls = max(1, steps // PHYSICS_CALL_STEPS)

    def physics_only():
        env.reset(seed=0, options={"eval_index": 4})
        for _ in range(calls):
            st.step(per_call, env.ACT_KIND)
    out["physics"] = _rate(physics_only, calls * PHYSICS_CALL_STEPS, repeats)
    out["iterations"] = {"commanded": _iterations(env, commanded), "fixed": _iterations(env, kernel_only)}
    ts = []
    for i in range(200):
        t0 = time.process_time()
        env.reset(seed=i)
        ts.append(time.process_time() - t0)
    out["reset_ms"] = statistics.median(ts) * 1e3
    ts = []
    for i in range(200):
        env.sim.advance_steps(1)
        t0 = time.perf_counter()
        env.sim.reset()
        ts.append(time.perf_counter() - t0)
    out["reset_sim_us"] = statistics.median(ts) * 1e6
    made.close()
    return out


def _commanded_kernel(env, acts, reset=True):
    """A run of the compiled step alone under the episode's commands: each step's action mapped to actuator
    commands as :meth:`TowEnv.step` maps it (``_commands``: clean, clip, scale or log-map), then the stepper's
    call; no observation, reward, info or Python step around it. A command that changes every control step
    costs the physics more Newton iterations than the fixed command of ``kernel_only`` (the actuator's jump
    must propagate through the cable), so this — not the fixed-command run — is the step's physics under the
    same actions as the env run. ``reset=False``: the caller resets (to keep the reset out of a timing)."""
    rows = env._rows
    st, A, amap = rows.stepper, rows.actions, rows.amap
    i = env._row
    idx = np.array([i])

    def f():
        if reset:
            env.reset(seed=0, options={"eval_index": 4})
        for a in acts:
            A[i] = a
            env._commands(A, idx, st.U, amap)
            st.step(env.substeps, env.ACT_KIND)
    return f


def _iterations(env, run):
    """Newton iterations per physics step of one ``run()`` (the simulator's counters)."""
    from towenv.core import layout as L
    run()                                   # (resets first; the counters are read after it)
    c = env.sim.kernel_data().counters
    return float(c[L.N_ITERATIONS]) / max(float(c[L.N_STEPS]), 1.0)


def _vec_rate(venv, steps, repeats, wall=False):
    acts = np.random.default_rng(0).uniform(-1, 1, (steps,) + venv.action_space.shape).astype(np.float32)

    def f():
        venv.reset(seed=0)
        for a in acts:
            venv.step(a)
    f()
    r = _rate(f, steps * venv.num_envs, repeats)
    return (r[3], r[3], r[3], r[3]) if wall else r


def bench_vector(env_id, sizes, steps, repeats, threads):
    import gymnasium as gym
    import numba
    res = {}
    for n in sizes:
        venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", batch_infos=True)
        res[("batched", n)] = _vec_rate(venv, steps, repeats)
        venv.close()
        if threads > 1:
            numba.set_num_threads(threads)
            venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", parallel=True)
            res[("prange", n)] = _vec_rate(venv, steps, repeats, wall=True)
            venv.close()
            numba.set_num_threads(1)
    return res


def bench_loops(env_id, n, steps, repeats):
    import gymnasium as gym
    res = {}
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync")
    res["SyncVectorEnv"] = _vec_rate(venv, steps, repeats)
    venv.close()
    try:
        from stable_baselines3.common.env_util import make_vec_env
        from towenv.envs.sb3 import TowSB3VecEnv
    except ImportError:
        return res
    for name, make in (("SB3 DummyVecEnv", lambda: make_vec_env(env_id, n_envs=n, seed=0)),
                       ("SB3 TowSB3VecEnv (batched)", lambda: TowSB3VecEnv(env_id, n, seed=0))):
        ve = make()
        acts = np.random.default_rng(0).uniform(-1, 1, (steps, n) + ve.action_space.shape).astype(np.float32)

        def g():
            ve.reset()
            for a in acts:
                ve.step(a)
        g()
        res[name] = _rate(g, steps * n, repeats)
        ve.close()
    return res


def bench_pendulum(steps, repeats):
    """Gymnasium's Pendulum-v1 with the same number of random-action steps (the issue's yardstick)."""
    import gymnasium as gym
    made = gym.make("Pendulum-v1")
    acts = np.random.default_rng(0).uniform(-2, 2, (steps, 1)).astype(np.float32)

    def run(e):
        def f():
            e.reset(seed=0)
            for a in acts:
                e.step(a)
        return f
    return {"unwrapped": _rate(run(made.unwrapped), steps, repeats), "gym.make": _rate(run(made), steps, repeats)}


def bench_paired(env_id, steps, repeats):
    """Per-pair CPU-time ratios (towenv step / Pendulum-v1 step), unwrapped, the two runs alternating: this host
    switches between a fast and a slow state for seconds at a time, and figures taken minutes apart (the tables
    above) can put the two in different states; alternating runs of ``steps`` steps each cannot."""
    import gymnasium as gym
    made = gym.make(env_id)
    env = made.unwrapped
    pend = gym.make("Pendulum-v1").unwrapped
    acts = np.random.default_rng(0).uniform(-1, 1, (steps,) + env.action_space.shape).astype(np.float32)
    pacts = np.random.default_rng(0).uniform(-2, 2, (steps, 1)).astype(np.float32)

    def cpu(e, a, **kw):
        e.reset(seed=0, **kw)
        c0 = time.process_time()
        for x in a:
            e.step(x)
        return time.process_time() - c0
    st = env._rows.stepper
    per_call = PHYSICS_CALL_STEPS * env.substeps
    calls = max(1, steps // PHYSICS_CALL_STEPS)

    def cpu_kernel(n, k):
        env.reset(seed=0, options={"eval_index": 4})
        c0 = time.process_time()
        for _ in range(k):
            st.step(n, env.ACT_KIND)
        return time.process_time() - c0
    commanded = _commanded_kernel(env, acts, reset=False)

    def cpu_commanded():                       # reset outside the timing, as in cpu() and cpu_kernel()
        env.reset(seed=0, options={"eval_index": 4})
        c0 = time.process_time()
        commanded()
        return time.process_time() - c0
    cpu(env, acts, options={"eval_index": 4})
    ratios, parts = [], []
    for _ in range(max(3, 2 * repeats)):
        tp = cpu(pend, pacts) / steps
        te = cpu(env, acts, options={"eval_index": 4}) / steps
        tk = cpu_kernel(env.substeps, steps) / steps
        tph = cpu_kernel(per_call, calls) / (calls * PHYSICS_CALL_STEPS)
        tkc = cpu_commanded() / steps
        ratios.append(te / tp)
        # the step's physics under the episode's commands (the zero-overhead bound): the fixed-command physics
        # plus what the changing commands add (commanded − fixed-command compiled step: the same calls)
        tb = tph + (tkc - tk)
        parts.append((te / tp, tb / tp, (tk - tph) / tp, (te - tkc) / tp, 1e6 * te, 1e6 * tb, 1e6 * (tk - tph),
                      1e6 * (te - tkc), 1e6 * tph, 1e6 * (tkc - tk), tph / tp))
    made.close()
    # per-pair figures: [env step, physics under the episode's commands, per-call compiled costs, Python] as
    # multiples of the pair's Pendulum step, then the same in µs, then the fixed-command physics and what the
    # changing commands add (µs) and the fixed-command physics as a multiple; medians over the pairs
    med = [statistics.median(p[j] for p in parts) for j in range(11)]
    return statistics.median(ratios), min(ratios), max(ratios), med


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=2000, help="single-env control steps per run (default 2000)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--sizes", type=int, nargs="+", default=[1, 8, 32, 128], help="vector-env sizes N")
    ap.add_argument("--vector-steps", type=int, default=200, help="vector steps per run (default 200)")
    ap.add_argument("--loop-envs", type=int, default=8, help="N of the Python-loop comparisons (default 8)")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1, help="numba threads of the prange runs")
    args = ap.parse_args(argv)
    import numba
    import towenv.envs
    numba.set_num_threads(1)
    print(f"# towenv environment benchmark — {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, Python {platform.python_version()}, numba {numba.__version__}, one process")
    print(f"# 10 Hz control, dt = 0.05 s (2 physics sub-steps), coastal SS4 sea, random actions; median of "
          f"{args.repeats} runs by process CPU time (min–max; wall-clock median); load average at start "
          f"{os.getloadavg()[0]:.2f}\n")
    fmt = lambda r: f"{r[0]:,.0f} ({r[1]:,.0f}–{r[2]:,.0f}; wall {r[3]:,.0f})"   # noqa: E731
    singles, vecs, loops = {}, {}, {}
    for env_id in towenv.envs.ENV_IDS:
        singles[env_id] = bench_single(env_id, args.steps, args.repeats)
        vecs[env_id] = bench_vector(env_id, args.sizes, args.vector_steps, max(3, args.repeats // 2), args.threads)
        loops[env_id] = bench_loops(env_id, args.loop_envs, args.vector_steps, max(3, args.repeats // 2))
    print("## Single environment (env steps/s; one core)\n")
    print("| environment | unwrapped | gym.make | compiled step alone (kernel + gather) | physics alone "
          f"({PHYSICS_CALL_STEPS} control steps per call) | reset (ms) | Simulator.reset (µs) |")
    print("|---|---|---|---|---|---|---|")
    for env_id, s in singles.items():
        print(f"| {env_id} | {fmt(s['unwrapped'])} | {fmt(s['gym.make'])} | {fmt(s['kernel'])} | {fmt(s['physics'])} | "
              f"{s['reset_ms']:.2f} | {s['reset_sim_us']:.1f} |")
    print("\nWhere a single (unwrapped) env step goes, µs of CPU (medians above): the physics of the control step "
          "under the episode's random commands (the zero-overhead bound) = physics alone (fixed command) + what the "
          "changing commands add (compiled step under the episode's commands − compiled step alone: the same calls, "
          "more Newton iterations) ; per-call costs of the compiled step (kernel + gather − physics alone); Python "
          "around it (unwrapped − compiled step under the episode's commands). Newton iterations per physics step "
          "in the last column\n")
    print("| environment | env step | physics under the episode's commands | of which fixed-command physics | "
          "added by the changing commands | per-call compiled step costs | Python around it | Newton iterations "
          "per step (episode's / fixed commands) |")
    print("|---|---|---|---|---|---|---|---|")
    for env_id, s in singles.items():
        e, k, kc, ph = (1e6 / s[key][0] for key in ("unwrapped", "kernel", "kernel_cmd", "physics"))
        it = s["iterations"]
        print(f"| {env_id} | {e:.1f} | {ph + kc - k:.1f} | {ph:.1f} | {kc - k:.1f} | {k - ph:.1f} | {e - kc:.1f} | "
              f"{it['commanded']:.2f} / {it['fixed']:.2f} |")
    print("\n## Batched vector env, `vector_entry_point` (total env-steps/s)\n")
    heads = [f"N = {n}" for n in args.sizes]
    print("| environment | mode | " + " | ".join(heads) + " |")
    print("|---|---|" + "---|" * len(heads))
    for env_id, v in vecs.items():
        print(f"| {env_id} | serial (1 core, CPU time) | " + " | ".join(fmt(v[("batched", n)]) for n in args.sizes)
              + " |")
        if any(k[0] == "prange" for k in v):
            print(f"| {env_id} | prange, {args.threads} threads (wall clock) | "
                  + " | ".join(f"{v[('prange', n)][0]:,.0f}" for n in args.sizes) + " |")
    pend = bench_pendulum(args.steps, args.repeats)
    print("\n## Cost per env-step relative to Gymnasium `Pendulum-v1` in the same run (goals: single ≤ 3×, batched ≤ 1×)\n")
    print(f"Pendulum-v1: unwrapped {fmt(pend['unwrapped'])}, gym.make {fmt(pend['gym.make'])} steps/s\n")
    nmax = max(args.sizes)
    print(f"| environment | single, unwrapped | single, gym.make | batched serial N = {nmax} | single, unwrapped, "
          f"alternating runs (median, min–max of per-pair ratios) | physics under the episode's commands, alternating "
          f"(zero-overhead bound) | physics alone, fixed command |")
    print("|---|---|---|---|---|---|---|")
    paired = {}
    for env_id, s in singles.items():
        pr = bench_paired(env_id, args.steps, args.repeats)
        paired[env_id] = pr[3]
        print(f"| {env_id} | {pend['unwrapped'][0] / s['unwrapped'][0]:.2f}× | {pend['gym.make'][0] / s['gym.make'][0]:.2f}× "
              f"| {pend['unwrapped'][0] / vecs[env_id][('batched', nmax)][0]:.2f}× | {pr[0]:.2f}× ({pr[1]:.2f}–{pr[2]:.2f}) "
              f"| {pr[3][1]:.2f}× | {pr[3][10]:.2f}× |")
    print("\nThe single env step in the alternating runs, split as above (median over the pairs of each part's CPU "
          "time, in µs and as a multiple of the pair's Pendulum-v1 step; the parts need not add up to the median "
          "total):\n")
    print("| environment | env step | physics under the episode's commands (fixed-command physics + added) | "
          "per-call compiled step costs | Python around it |")
    print("|---|---|---|---|---|")
    for env_id, m in paired.items():
        print(f"| {env_id} | {m[4]:.1f} µs ({m[0]:.2f}×) | {m[5]:.1f} µs ({m[1]:.2f}×; {m[8]:.1f} + {m[9]:.1f}) "
              f"| {m[6]:.1f} µs ({m[2]:.2f}×) | {m[7]:.1f} µs ({m[3]:.2f}×) |")
    print(f"\n## Python loops over N = {args.loop_envs} single envs, for comparison (total env-steps/s)\n")
    names = list(next(iter(loops.values())))
    print("| environment | " + " | ".join(names) + " |")
    print("|---|" + "---|" * len(names))
    for env_id, lp in loops.items():
        print(f"| {env_id} | " + " | ".join(fmt(lp[k]) if k in lp else "n/a" for k in names) + " |")


if __name__ == "__main__":
    main()
