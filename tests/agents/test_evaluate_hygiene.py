"""Evaluation hygiene (issue 14, items 5-6): report folder default and refusal, atomic report files, the
no-verdict rule, the fresh ``final`` wave-seed set, and aggregation across training seeds (IQM and the
stratified bootstrap, checked against rliable when it runs and against hand-computed cases)."""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

from helpers import REPO, load_script
WINCH = "towenv/WinchPayout-v0"
COMP = "towenv/CompensatorGains-v0"



@pytest.fixture(scope="module")
def evaluate():
    return load_script("evaluate")


def _tmp_leftovers(folder: Path):
    return [p.name for p in folder.rglob(".*.tmp-*")]


# ---------------------------------------------------------------------------------------- synthetic results
def _synthetic_result(names_trained, n_entries=12, replicates=1, seed=0, offset=0, kind="winch", extra=None):
    """An EvalResult with made-up (but structurally real) per-episode metrics: every controller's
    episodes are synthetic time series run through agents.metrics.episode_metrics. ``extra``: more baselines,
    {name: heave amplitude} (the reference's is 1, best_passive's 0.7)."""
    from agents.common import sea_key, sea_label
    from agents.evaluation import Controller, EvalResult, assess_goals, summarize
    from agents.metrics import EpisodeRecord, episode_metrics
    from towenv.envs.pieces import default_eval_sea_states

    ev = default_eval_sea_states()
    episodes = []
    for i in range(n_entries):
        sea, s = ev[i]
        for r in range(replicates):
            episodes.append((sea_key(sea), sea_label(sea, 3 + i // 4), sea, s + offset + 100 * r))
    rng = np.random.default_rng(seed)
    bl = ["fixed_winch", "along_cable"] if kind == "winch" else ["locked", "best_passive"]
    amp = {"fixed_winch": 1.0, "along_cable": 0.5, "locked": 1.0, "best_passive": 0.7} | dict(extra or {})
    bl += list(extra or {})
    ctrls = [Controller(n, SimpleNamespace(), None, "trained", "synthetic", {"algo": "ppo", "seed": k})
             for k, n in enumerate(names_trained)]
    ctrls += [Controller(n, SimpleNamespace(), None, "baseline", "synthetic") for n in bl]
    t = np.arange(0.0, 120.0, 0.5)
    metrics = {}
    for c in ctrls:
        a = amp.get(c.name, 0.4 + 0.1 * rng.random())
        ms = []
        for j, (g, lab, sea, s) in enumerate(episodes):
            e = np.random.default_rng(s)             # same wave per episode for every controller
            wave = e.normal(size=t.size)
            noise = rng.normal(size=t.size)
            h = a * (0.5 + (j // 4)) * (wave + 0.2 * noise)
            data = {"t": t, "heave": h, "pitch": 0.02 * h, "heave_rate": np.gradient(h, t),
                    "pitch_rate": 0.02 * np.gradient(h, t), "tow_z": wave, "top_tension": 5e3 + 100 * h,
                    "min_tension": 50.0 + 0 * t, "reward": -h * h}
            if kind == "winch":
                data |= {"winch_speed": 0.1 * noise, "winch_dev": 0.5 * noise}
            else:
                data |= {"stroke": 0.1 * noise, "stroke_vel": 0 * t, "stiffness": 1e3 + 0 * t,
                         "damping": 1e3 + 0 * t, "hits": 0 * t}
            rec = EpisodeRecord(kind, sea, s, 0.5, data, steps=t.size, winch_travel=10.0, half_stroke=1.0)
            ms.append(episode_metrics(rec, 20.0))
        metrics[c.name] = ms
    ref = bl[0]
    for c in ctrls:
        for m, r in zip(metrics[c.name], metrics[ref]):
            m["cr_heave"] = 1.0 - m["rms_heave"] / r["rms_heave"]
            m["cr_heave_sp"] = 1.0 - m["rms_heave_sp"] / r["rms_heave_sp"]
            m["cr_pitch"] = 1.0 - m["rms_pitch_deg"] / r["rms_pitch_deg"]
    env_id = WINCH if kind == "winch" else COMP
    res = EvalResult(env_id, kind, {}, episodes, ctrls, metrics, {c.name: {} for c in ctrls}, ref, 20.0, 1.0)
    res.summary = summarize(res, 50)
    res.goals = assess_goals(res, 50)
    return res


# ---------------------------------------------------------------------------------------- out-dir, refusal
def test_out_dir_default_refusal_and_force(tmp_path, monkeypatch, capsys, evaluate):
    assert evaluate.parse_args(["fixed_winch"]).out_dir == os.path.join("runs", "reports")
    monkeypatch.chdir(tmp_path)
    docs = REPO / "docs" / "reports"
    before = {p: p.stat().st_mtime_ns for p in docs.rglob("*")} if docs.exists() else {}
    argv = ["fixed_winch", "--env", WINCH, "--episodes", "0", "--env-kwargs", "episode_seconds:20",
            "--no-plots", "--baselines", "--boot", "20"]
    assert evaluate.main(argv) == 0
    rep = tmp_path / "runs" / "reports" / "baselines_WinchPayout-v0"
    assert {p.name for p in rep.iterdir()} == {"report.md", "metrics.csv", "summary.json"}
    first = (rep / "summary.json").read_text()
    capsys.readouterr()
    with pytest.raises(SystemExit) as e:            # exists: refused before any evaluation
        evaluate.main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "exists" in err[0] and "--force" in err[0]
    assert (rep / "summary.json").read_text() == first
    assert evaluate.main(argv + ["--force", "--seed-set", "final"]) == 0
    s = json.loads((rep / "summary.json").read_text())
    assert s["wave_seeds"] == [23000] and "final" in s["seed_set"]
    assert "**final** set" in (rep / "report.md").read_text()
    assert not _tmp_leftovers(tmp_path)
    after = {p: p.stat().st_mtime_ns for p in docs.rglob("*")} if docs.exists() else {}
    assert after == before                          # the committed reports were not touched


@pytest.mark.parametrize("argv", [
    ["fixed_winch", "--env", WINCH, "--episodes", "0", "99"],
    ["fixed_winch", "--env", WINCH, "--replicates", "0"],
    ["fixed_winch", "--env", WINCH, "--replicates", "6"],                 # eval set + 500 = tuning seeds
    ["fixed_winch", "--env", WINCH, "--seed-set", "fresh"],
    ["fixed_winch", "--env", WINCH, "--episodes", "zero"],
    ["fixed_winch", "--env", WINCH, "--env-kwargs", "no_such_keyword:1"],
    ["fixed_winch", "--env", WINCH, "--env-kwargs", "novalue"],
    ["fixed_winch", "--env", WINCH, "--baselines", "best_passive"],
    ["fixed_winch", "--env", WINCH, "--name", "../elsewhere"],
    ["no_such_policy.zip"],
])
def test_bad_input_is_one_line_exit_2(argv, tmp_path, monkeypatch, capsys, evaluate):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as e:
        evaluate.main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "error" in err and "Traceback" not in err
    assert not (tmp_path / "runs").exists()


# ---------------------------------------------------------------------------------------- verdicts
def test_no_verdict_below_minimum(tmp_path):
    from agents.report import MIN_VERDICT_EPISODES, verdict, write_report
    assert MIN_VERDICT_EPISODES == 24
    g = {"met": True}
    assert verdict(g, 23) == "no verdict: 23 episodes < 24"
    assert verdict(g, 24) == "MET" and verdict({"met": False}, 48) == "not met"

    few = _synthetic_result(["ppo_a"], n_entries=12, replicates=1)
    md = write_report(few, tmp_path / "few", "t", plots=False).read_text()
    assert "no verdict: 12 episodes < 24" in md and "**met**" not in md and "**not met**" not in md
    s = json.loads((tmp_path / "few" / "summary.json").read_text())
    assert s["n_episodes"] == 12 and all(gd["verdict"] == "no verdict: 12 episodes < 24" for gd in s["goals"])
    assert all(math.isfinite(gd["value"][0]) for gd in s["goals"])        # the figures are still there

    enough = _synthetic_result(["ppo_a"], n_entries=12, replicates=2)
    md = write_report(enough, tmp_path / "enough", "t", plots=False).read_text()
    assert "no verdict" not in md and ("**met**" in md or "**not met**" in md)
    s = json.loads((tmp_path / "enough" / "summary.json").read_text())
    assert {gd["verdict"] for gd in s["goals"]} <= {"MET", "not met"}


@pytest.mark.parametrize("bound_amp, applies", [(0.3, False), (0.65, True)])
def test_alternative_compensator_criterion_only_where_the_bound_misses_15_percent(tmp_path, bound_amp, applies):
    """The compensator goal's "within 80 % of the clairvoyant active bound" is the issue's fallback for a bound
    below 15 %: with a bound of 57 % below best_passive (amplitude 0.3 against 0.7) its row says "not applicable"
    (no met / not met beside the 15 % criteria); with a bound of ~7 % (0.65) it gets a verdict."""
    from agents.report import NOT_APPLICABLE, verdict, write_report
    res = _synthetic_result(["gn_a"], replicates=2, kind="compensator", extra={"clairvoyant_active": bound_amp})
    alt = [g for g in res.goals if g["criterion"].startswith("within 80 %")]
    assert len(alt) == 1 and alt[0]["bound_below_goal"] is applies
    assert (alt[0]["bound"][0] < 0.15) is applies
    assert (verdict(alt[0], 24) == NOT_APPLICABLE) is not applies
    assert verdict(alt[0], 24) in ({"MET", "not met"} if applies else {NOT_APPLICABLE})
    assert verdict(alt[0], 23).startswith("no verdict")                 # the episode minimum still comes first
    others = [g for g in res.goals if g is not alt[0] and g["policy"] == "gn_a"]
    assert others and all(verdict(g, 24) in ("MET", "not met") for g in others)
    md = write_report(res, tmp_path / "r", "t", plots=False).read_text()
    row = next(line for line in md.splitlines() if "within 80 %" in line and "`gn_a`" in line)
    assert (NOT_APPLICABLE in row) is not applies
    s = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert [gd["verdict"] for gd in s["goals"] if gd["criterion"].startswith("within 80 %")] == [verdict(alt[0], 24)]


def test_evaluate_prints_no_verdict(tmp_path, monkeypatch, capsys, evaluate):
    """main() end to end with run_evaluation replaced by a synthetic one (which still builds its episode
    list with agents.evaluation.eval_episodes, so the final set's offset is exercised)."""
    import agents.evaluation as ev

    calls = {}

    def fake_run(env_id, trained, replicates=1, indices=None, **kw):
        env = ev.make_eval_env(env_id, kw.get("env_kwargs"))
        eps = ev.eval_episodes(env, replicates, indices)
        calls["seeds"] = [e[3] for e in eps]
        assert list(indices) == list(range(len(indices)))
        res = _synthetic_result(["ppo_a"], n_entries=len(indices), replicates=replicates)
        res.episodes = eps
        return res

    monkeypatch.setattr(ev, "run_evaluation", fake_run)
    monkeypatch.chdir(tmp_path)
    assert evaluate.main(["fixed_winch", "--env", WINCH, "--episodes", "0", "1", "--no-plots",
                          "--seed-set", "final", "--replicates", "2"]) == 0
    out = capsys.readouterr().out
    assert calls["seeds"] == [23000, 23100, 23001, 23101]
    assert "no verdict: 4 episodes < 24" in out and "MET" not in out and "not met" not in out
    assert ev.eval_episodes.__name__ == "eval_episodes"            # the offset patch is undone


# ---------------------------------------------------------------------------------------- seed sets
@pytest.mark.parametrize("env_id", [WINCH, COMP])
def test_final_seed_set_is_fresh(env_id, evaluate):
    from agents.evaluation import eval_episodes, make_eval_env
    from agents.tuning import TUNING_SEED_OFFSET, tuning_seas
    train = load_script("train")
    env = make_eval_env(env_id, {})
    base = [s for _, s in env.unwrapped.eval_sea_states()]
    eval_seeds = {e[3] for r in range(1, evaluate.MAX_EVAL_REPLICATES + 1) for e in eval_episodes(env, r)}
    tuning = {s for _, s in tuning_seas(env)}
    hover = {s + 400 for s in tuning}                       # agents/tuning.py: design seed = tuning seed + 400
    validation = {s for _, s in train.validation_seas(env_id, {}, len(base))}
    env.close()
    assert TUNING_SEED_OFFSET == evaluate.RESERVED_OFFSETS["tuning"]
    for reps in (1, 2, 5, 10):
        final = evaluate.episode_seeds(base, "final", reps)
        assert len(set(final)) == len(final)
        for other in (eval_seeds, tuning, hover, validation):
            assert not set(final) & other
        assert evaluate.check_seed_set(base, base, "final", reps) is None
    # the eval list is today's list
    assert evaluate.episode_seeds(base, "eval", 2) == [e[3] for e in eval_episodes(make_eval_env(env_id, {}), 2)]
    # the eval set with too many replicates reaches the tuning seeds and is refused
    assert evaluate.check_seed_set(base, base, "eval", evaluate.MAX_EVAL_REPLICATES) is None
    assert "tuning" in evaluate.check_seed_set(base, base, "eval", evaluate.MAX_EVAL_REPLICATES + 1)


# ---------------------------------------------------------------------------------------- aggregation
def test_iqm_hand_computed():
    from agents.aggregate import iqm, mean, median
    assert iqm(np.arange(1.0, 9.0)) == pytest.approx(4.5)              # mean of 3, 4, 5, 6
    x = np.array([[0.0, 100.0, 1.0, 2.0], [3.0, 4.0, -50.0, 5.0]])     # 8 scores: the 2 lowest, 2 highest cut
    assert iqm(x) == pytest.approx(np.mean([1.0, 2.0, 3.0, 4.0]))
    assert mean(x) == pytest.approx(x.mean())
    assert median(x) == pytest.approx(np.median(x.mean(axis=0)))


@pytest.mark.parametrize("backend", ["numpy", "rliable"])
def test_stratified_bootstrap_hand_computed(backend):
    from agents.aggregate import rliable_available, stratified_bootstrap_ci
    if backend == "rliable" and not rliable_available():
        pytest.skip("rliable does not run here")
    # task 2 is the same for both runs; task 1 has runs 0 and 2: the resampled mean is (m1 + 10)/2 with
    # m1 in {0, 1, 2} at probabilities 1/4, 1/2, 1/4 -> point 5.5, 95 % CI [5, 6]
    s = np.array([[0.0, 10.0], [2.0, 10.0]])
    p, lo, hi = stratified_bootstrap_ci(s, "mean", reps=4000, backend=backend)
    assert (p, lo, hi) == pytest.approx((5.5, 5.0, 6.0))
    # runs resampled within tasks only: rows that are constant per task give a zero-width CI
    # (a bootstrap over all cells would not)
    s = np.array([[1.0, 5.0, 9.0]] * 4)
    assert stratified_bootstrap_ci(s, "iqm", reps=500, backend=backend) == pytest.approx((5.0, 5.0, 5.0))
    # one run: the CI collapses to the point
    assert stratified_bootstrap_ci(np.array([[1.0, 2.0, 3.0]]), "mean") == pytest.approx((2.0, 2.0, 2.0))
    # reproducible with a seed
    r = np.random.default_rng(3).normal(size=(3, 12))
    assert stratified_bootstrap_ci(r, "iqm", reps=300, seed=7, backend=backend) == \
        stratified_bootstrap_ci(r, "iqm", reps=300, seed=7, backend=backend)


def test_bootstrap_matches_rliable():
    from agents.aggregate import rliable_available, stratified_bootstrap_ci
    if not rliable_available():
        pytest.skip("rliable does not import or run here (rliable 1.2 needs arch < 8, arch 7 needs pandas < 3)")
    from rliable import metrics as rm
    rng = np.random.default_rng(1)
    s = rng.normal(size=(3, 24)) + np.linspace(0.0, 2.0, 24)
    for name, ref in (("iqm", rm.aggregate_iqm), ("mean", rm.aggregate_mean), ("median", rm.aggregate_median)):
        a = stratified_bootstrap_ci(s, name, reps=20000, backend="rliable")
        b = stratified_bootstrap_ci(s, name, reps=20000, backend="numpy")
        assert a[0] == pytest.approx(float(ref(s))) and b[0] == pytest.approx(a[0])
        width = a[2] - a[1]
        assert b[1] == pytest.approx(a[1], abs=0.03 * width) and b[2] == pytest.approx(a[2], abs=0.03 * width)


def test_aggregate_policies_and_bad_input():
    from agents.aggregate import aggregate_policies, iqm, stratified_bootstrap_ci
    rng = np.random.default_rng(0)
    d = aggregate_policies({"a": rng.normal(size=(3, 10)), "b": rng.normal(size=(5, 10)) + 1.0}, reps=200)
    assert set(d) == {"a", "b"} and d["b"]["n_runs"] == 5 and d["a"]["n_tasks"] == 10
    for v in d.values():
        for k in ("iqm", "mean", "median"):
            p, lo, hi = v[k]
            assert lo <= p <= hi
    assert d["b"]["iqm"][0] > d["a"]["iqm"][0]
    with pytest.raises(ValueError):
        stratified_bootstrap_ci(np.array([[1.0, np.nan]]), "iqm")
    with pytest.raises(ValueError):
        stratified_bootstrap_ci(np.ones((2, 2)), "nope")
    assert iqm([[1.0, 2.0], [3.0, 4.0]]) == pytest.approx(2.5)


def test_across_training_seeds_section(tmp_path):
    from agents.aggregate import across_seeds, iqm, seed_groups
    from agents.report import write_report
    names = ["ppo_W_s0", "ppo_W_seed1", "ppo_W_s2", "sac_W_s0", "ppo_other"]
    groups = seed_groups(names)
    assert groups == {"ppo_W": [("ppo_W_s0", 0), ("ppo_W_seed1", 1), ("ppo_W_s2", 2)], "sac_W": [("sac_W_s0", 0)]}
    res = _synthetic_result(names, n_entries=12, replicates=2)
    g = across_seeds(res, groups["ppo_W"], "ppo_W", reps=200)
    assert g["n_seeds"] == 3 and g["n_tasks"] == 24 and g["baseline"] == "along_cable"
    x = np.array([[m["rms_heave"] for m in res.metrics[n]] for n, _ in groups["ppo_W"]])
    assert g["metrics"]["rms_heave"]["iqm"][0] == pytest.approx(iqm(x))
    b = np.array([m["rms_heave"] for m in res.metrics["along_cable"]])
    red = g["metrics"]["reduction_vs_along_cable"]["iqm"]
    assert red[0] == pytest.approx(iqm(1.0 - x / b)) and red[1] <= red[0] <= red[2]
    assert g["per_seed"]["ppo_W_s2"]["reduction_vs_along_cable"] == pytest.approx(1.0 - x[2].mean() / b.mean())
    md = write_report(res, tmp_path / "r", "t", plots=False, across_seeds=[g]).read_text()
    assert "## Across training seeds" in md and "3 training seeds" in md and "at least 3" not in md
    two = across_seeds(res, groups["ppo_W"][:2], "ppo_W", reps=100)
    md = write_report(res, tmp_path / "r2", "t", plots=False, across_seeds=[two]).read_text()
    assert "2 training seeds" in md and "at least 3" in md
    s = json.loads((tmp_path / "r2" / "summary.json").read_text())
    assert s["across_seeds"][0]["n_seeds"] == 2


# ---------------------------------------------------------------------------------------- atomic files
def test_atomic_write_leaves_no_partial_file(tmp_path):
    from agents.report import atomic_write
    p = tmp_path / "x.json"
    atomic_write(p, "old")

    def half(f):
        f.write("partial")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        atomic_write(p, half)
    assert p.read_text() == "old" and sorted(q.name for q in tmp_path.iterdir()) == ["x.json"]
    with pytest.raises(RuntimeError):
        atomic_write(tmp_path / "new.json", half)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["x.json"]


def test_report_writer_failure_keeps_previous_report(tmp_path, monkeypatch):
    import agents.report as report
    res = _synthetic_result(["ppo_a"], n_entries=4)
    out = tmp_path / "rep"
    report.write_report(res, out, "first", plots=False, html_too=True)
    old = {p.name: p.read_bytes() for p in out.iterdir()}
    assert set(old) == {"report.md", "metrics.csv", "summary.json", "report.html"}

    def broken_csv(res, f):
        f.write("controller,episode\nppo_a,0\n")
        raise OSError("interrupted")

    monkeypatch.setattr(report, "_write_metrics_csv", broken_csv)
    with pytest.raises(OSError):
        report.write_report(res, out, "second", plots=False, html_too=True)
    assert (out / "metrics.csv").read_bytes() == old["metrics.csv"]        # not half a file
    assert (out / "summary.json").read_bytes() == old["summary.json"]      # summary.json (last) untouched
    assert not _tmp_leftovers(out)
    monkeypatch.undo()

    monkeypatch.setattr(report, "_summary_json", lambda *a, **k: (_ for _ in ()).throw(ValueError("boom")))
    with pytest.raises(ValueError):
        report.write_report(res, out, "third", plots=False)
    assert (out / "summary.json").read_bytes() == old["summary.json"]
    assert "# third" in (out / "report.md").read_text()                    # written before, atomically
    assert not _tmp_leftovers(out)
    monkeypatch.undo()
    report.write_report(res, out, "fourth", plots=False)                   # no --html: the stale html goes
    assert not (out / "report.html").exists() and "# fourth" in (out / "report.md").read_text()


# ------------------------------------------------------------------------------------------ --reuse
def test_reuse_takes_rows_only_from_a_report_of_the_same_physics(tmp_path, evaluate, monkeypatch, capsys):
    """--reuse BASELINE=DIR: the baseline is not run, its rows are the earlier report's; refused (exit 2) when the
    episodes differ or when a controller both runs share disagrees with the earlier report."""
    import csv
    monkeypatch.chdir(tmp_path)
    quick = ["--env", WINCH, "--no-plots", "--env-kwargs", "episode_seconds:30", "--discard", "10"]
    assert evaluate.main(["along_cable", "--episodes", "0", "5", "--baselines", "fixed_winch", "along_cable",
                          "--name", "a", *quick]) == 0
    a = tmp_path / "runs" / "reports" / "a"
    capsys.readouterr()
    assert evaluate.main(["along_cable", "--episodes", "0", "5", "--baselines", "fixed_winch", "along_cable",
                          "--name", "b", "--reuse", f"along_cable={a}", *quick]) == 0
    out = capsys.readouterr().out
    assert "along_cable: 2 episodes reused from" in out and "reuse check for along_cable: fixed_winch agree" in out
    b = tmp_path / "runs" / "reports" / "b"

    def rows(folder, name):
        with open(folder / "metrics.csv", newline="") as f:
            return [r for r in csv.DictReader(f) if r["controller"] == name]
    ra, rb = rows(a, "along_cable"), rows(b, "along_cable")
    assert [r["rms_heave"] for r in ra] == [r["rms_heave"] for r in rb] and len(ra) == 2
    assert json.loads((b / "summary.json").read_text())["reused"]["along_cable"]["checked_against"] == ["fixed_winch"]
    assert "Reused rows" in (b / "report.md").read_text()
    # a report that reused the rows lends them again (its description compared without its reuse note), and the
    # new report names both folders
    from agents.evaluation import REUSED_MARK, reused_origin
    desc_b = json.loads((b / "summary.json").read_text())["controllers"]["along_cable"]["description"]
    assert REUSED_MARK in desc_b and reused_origin(desc_b)[1] == str(a)
    assert evaluate.main(["along_cable", "--episodes", "0", "5", "--baselines", "fixed_winch", "along_cable",
                          "--name", "b2", "--reuse", f"along_cable={b}", *quick]) == 0
    b2 = tmp_path / "runs" / "reports" / "b2"
    desc_b2 = json.loads((b2 / "summary.json").read_text())["controllers"]["along_cable"]["description"]
    assert reused_origin(desc_b2) == (reused_origin(desc_b)[0], str(b)) and f"which reused them from {a}" in desc_b2
    assert [r["rms_heave"] for r in rows(b2, "along_cable")] == [r["rms_heave"] for r in ra]
    capsys.readouterr()
    # a report of another version (other metric columns): refused before any episode runs
    import shutil
    import agents.evaluation as evaluation
    old_cols = tmp_path / "old_columns"
    shutil.copytree(a, old_cols)
    lines = (old_cols / "metrics.csv").read_text().splitlines()
    drop = lines[0].split(",").index("winch_peak_power_kw")
    (old_cols / "metrics.csv").write_text("\n".join(",".join(c for j, c in enumerate(line.split(",")) if j != drop)
                                                     for line in lines) + "\n")
    monkeypatch.setattr(evaluation, "rollout", lambda *a, **k: pytest.fail("an episode ran before the column check"))
    with pytest.raises(SystemExit) as ex:
        evaluate.main(["along_cable", "--episodes", "0", "5", "--baselines", "fixed_winch", "along_cable",
                       "--name", "g", "--reuse", f"along_cable={old_cols}", *quick])
    assert ex.value.code == 2 and "metric columns differ from this version's (winch_peak_power_kw)" in capsys.readouterr().err
    monkeypatch.undo()
    monkeypatch.chdir(tmp_path)
    # other episodes: refused before anything is written
    with pytest.raises(SystemExit) as ex:
        evaluate.main(["along_cable", "--episodes", "1", "5", "--baselines", "fixed_winch", "along_cable",
                       "--name", "c", "--reuse", f"along_cable={a}", *quick])
    assert ex.value.code == 2 and "episode 0 differs" in capsys.readouterr().err
    assert not (tmp_path / "runs" / "reports" / "c").exists()
    # a tampered shared row (the reference ran on other physics): refused
    text = (a / "metrics.csv").read_text().splitlines()
    fw = next(i for i, line in enumerate(text) if line.startswith("fixed_winch,0,"))
    hdr = text[0].split(",")
    cells = text[fw].split(",")
    k = hdr.index("rms_heave")
    cells[k] = f"{float(cells[k]) * 1.001:.6g}"
    text[fw] = ",".join(cells)
    (a / "metrics.csv").write_text("\n".join(text) + "\n")
    with pytest.raises(SystemExit) as ex:
        evaluate.main(["along_cable", "--episodes", "0", "5", "--baselines", "fixed_winch", "along_cable",
                       "--name", "d", "--reuse", f"along_cable={a}", *quick])
    assert ex.value.code == 2 and "not the same physics" in capsys.readouterr().err
    # other environment keywords (a faster winch: fixed_winch alone would not tell): refused
    with pytest.raises(SystemExit) as ex:
        evaluate.main(["along_cable", "--episodes", "0", "5", "--baselines", "fixed_winch", "along_cable",
                       "--name", "f", "--reuse", f"along_cable={a}", "--env", WINCH, "--no-plots", "--discard", "10",
                       "--env-kwargs", "episode_seconds:30", "winch_max_speed:3.0"])
    assert ex.value.code == 2 and "environment keywords" in capsys.readouterr().err
    # bad forms: no folder, not a report, not a baseline of the run, the reference, a bare flag
    for bad in (["--reuse", "along_cable"], ["--reuse", f"along_cable={tmp_path / 'nowhere'}"],
                ["--reuse", f"pd_ff={a}"], ["--reuse", f"fixed_winch={a}"], ["--reuse"]):
        with pytest.raises(SystemExit) as ex:
            evaluate.main(["along_cable", "--episodes", "0", "5", "--baselines", "fixed_winch", "along_cable",
                           "--name", "e", *bad, *quick])
        assert ex.value.code == 2


@pytest.mark.parametrize("report, family, loader", [
    ("gnr_WinchPayout-v0", "gnr_WinchPayout-v0", "ars"),
    ("gns_CompensatorGains-v0", "gns_CompensatorGains-v0", "ars_compensator"),
])
def test_trained_description_matches_committed_reports(report, family, loader):
    """The report's description of a trained policy (feature set, hinge thresholds read from ars.HINGES, gated copy,
    iterations, start, seed) is a function of the policy file's metadata: the committed files reproduce the
    committed reports' text exactly (a change of the thresholds or of the wording shows here)."""
    import importlib

    import agents
    from agents.evaluation import trained_description
    repo = Path(__file__).resolve().parents[2]
    summary = json.loads((repo / "docs" / "reports" / report / "summary.json").read_text())
    mod = importlib.import_module(f"agents.{loader}")
    load = mod.load_ars_policy if loader == "ars" else mod.load_policy
    for seed in range(3):
        name = f"{family}_s{seed}"
        pol = load(Path(agents.__file__).parent / "trained" / f"{name}.npz")
        assert trained_description(pol.meta) == summary["controllers"][name]["description"]
    if loader == "ars":
        assert "beyond 1.0 and 1.5 m/s²" in summary["controllers"][f"{family}_s0"]["description"]
