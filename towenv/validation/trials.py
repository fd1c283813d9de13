"""Case 5: the full-scale trials (thesis §6.4, Tables A3/A4, Table 6.1): single vs two-part tow in the
Trial 2 conditions, scored against the sonar rate limits — as far as the printed inputs allow."""
from __future__ import annotations

import copy

import numpy as np

from ..scene import load_scene
from .common import CaseContext, Figure, Table, fmt, motion_rates, rate_exceedance, run_scene, savefig
from .reference import TABLE_6_1, TABLE_6_2_3, THESIS, TRIAL_REDUCTION_PCT

KNOT = 0.514444
DIRECTIONS = {"into": 180.0, "across": 90.0, "with": 0.0}


def trial_scenes(speed_kn=5.6, direction="into", seed=0, sea=None, fish_damping=None, junction=None):
    """(single, two_part) scene dicts for a Trial 2 run: 20 m primary; two-part adds a 10 m secondary."""
    tp1 = load_scene("two_part_tow_1").to_dict()
    tp2 = load_scene("two_part_tow_2").to_dict()
    fish = copy.deepcopy(next(b for b in tp1["bodies"] if b["name"] == "fish"))
    if fish_damping is not None:
        fish["rotational_damping"] = [fish_damping] * 3
    sea = sea or {"code": 3, "convention": "coastal", "spectrum": "jonswap"}
    common = {"water": tp1["water"],
              "sea": dict(sea, heading_deg=DIRECTIONS[direction], seed=seed, spreading_s=10.0),
              "vessel": {"speed": speed_kn * KNOT, "model": "coastal_survey",
                         "ramp": {"type": "half_cosine", "duration": 20.0}},
              "solver": {"dt": 0.05}}
    prim = copy.deepcopy(tp1["lines"][0])
    prim.update(length=20.0, segments=4, bottom={"body": "fish"})
    single = dict(name="trial_single", lines=[prim], bodies=[fish], **copy.deepcopy(common))
    p2 = copy.deepcopy(tp2["lines"][0])
    s2 = copy.deepcopy(tp2["lines"][1])
    p2.update(length=20.0, segments=4)
    s2.update(length=10.0, segments=2)
    bodies = [b if b["name"] != "fish" else copy.deepcopy(fish) for b in copy.deepcopy(tp2["bodies"])]
    if junction is not None:         # secondary from a junction `junction` m above the depressor
        p2.update(segments=[3, 1])
        s2.update(top={"line": p2["name"], "distance": 20.0 - junction})
    two = dict(name="trial_two_part", lines=[p2, s2], bodies=bodies, **copy.deepcopy(common))
    return single, two


def _score(res):
    ex = rate_exceedance(motion_rates(res, "fish"), TABLE_6_1)
    ex["depth"] = float(-res.bodies["fish"]["position"][:, 2].mean())
    line = "secondary" if "secondary" in res.lines else "primary"
    tf = res.lines[line]["tensions"][:, -1]
    ex["fish_cable_slack_pct"] = 100.0 * float(np.mean(tf <= 1e-6))
    ex["fish_cable_T_mean"] = float(tf.mean())
    return ex


def run(ctx: CaseContext) -> dict:
    quick = ctx.quick
    dur, t_skip = (250.0, 50.0) if quick else (700.0, 100.0)
    cases = [(5.6, d, "baseline") for d in (("into", "across") if quick else ("into", "across", "with"))]
    if not quick:
        cases += [(8.0, d, "baseline") for d in ("into", "across", "with")]
        cases += [(5.6, "into", "fish damping 1.0"), (5.6, "across", "fish damping 1.0"),
                  (5.6, "into", "open-ocean SS3 (Tp 7.5 s)"), (5.6, "into", "junction 5 m above the depressor")]
    bar = ctx.bar(2 * len(cases), "trials")
    rows, values, recs = [], {}, {}
    for kn, direc, variant in cases:
        kw = {}
        if variant == "fish damping 1.0":
            kw["fish_damping"] = 1.0
        elif variant.startswith("open-ocean"):
            kw["sea"] = {"code": 3, "convention": "open_ocean", "spectrum": "jonswap"}
        elif variant.startswith("junction"):
            kw["junction"] = 5.0
        sc = trial_scenes(kn, direc, **kw)
        sc_out = {}
        for tow, scene in zip(("single", "two-part"), sc):
            out = run_scene(scene, dur)
            bar.step(f"{tow} {kn} kn {direc} {variant[:10]}")
            if not out.ok:
                sc_out[tow] = None
                continue
            res = out.result.window(t_skip)
            sc_out[tow] = _score(res)
            if variant == "baseline" and kn == 5.6 and direc == "into":
                recs[tow] = res
        s, t = sc_out["single"], sc_out["two-part"]
        red = (100 * (1 - t["any"]["pct_over"] / s["any"]["pct_over"]) if s and t and s["any"]["pct_over"] > 0
               else None)
        for tow, e in (("single", s), ("two-part", t)):
            if e is None:
                rows.append([f"{kn} kn", direc, variant, tow, "diverged"] + [""] * 11)
                continue
            rows.append([f"{kn} kn", direc, variant, tow, e["depth"]] +
                        [e[m]["pct_over"] for m in ("roll", "pitch", "yaw", "surge", "sway", "heave", "any")] +
                        [e["pitch"]["rms"], e["fish_cable_T_mean"], e["fish_cable_slack_pct"],
                         (f"{red:.0f} %" if red is not None else "—") if tow == "two-part" else ""])
        values[f"{kn}kn/{direc}/{variant}"] = {"single": s, "two-part": t, "reduction_pct": red}
    bar.close()
    ref_rows = [[k] + [v[m] for m in ("roll", "pitch", "yaw", "surge", "sway", "heave", "any")]
                for k, v in TABLE_6_2_3.items()]
    base = [v for k, v in values.items() if k.endswith("baseline") and v["reduction_pct"] is not None]
    n_red = sum(1 for v in base if v["reduction_pct"] > 0)
    claims = [{"claim": "The two-part tow reduces the time any Table 6.1 rate limit is exceeded, against the single "
                        f"tow (Tables 6.2/6.3: by {TRIAL_REDUCTION_PCT['Trial 1']:.1f} % in Trial 1 and "
                        f"{TRIAL_REDUCTION_PCT['Trial 2']:.1f} % in Trial 2)",
               "holds": len(base) > 0 and n_red == len(base),
               "evidence": f"reduced in {n_red} of {len(base)} baseline conditions where the single tow exceeds a limit: "
                           + ", ".join(f"{k.split('/')[0]} {k.split('/')[1]}: {v['reduction_pct']:+.0f} %"
                                       for k, v in values.items() if k.endswith("baseline")
                                       and v["reduction_pct"] is not None)}]
    r1 = [v["roll"] for k, v in TABLE_6_2_3.items() if "single" in k]
    y1 = [v["yaw"] for k, v in TABLE_6_2_3.items() if "single" in k]
    depth_single = values["5.6kn/into/baseline"]["single"]["depth"]
    sc1 = load_scene("two_part_tow_1")
    fish_wet = sc1.body("fish").wet_weight(sc1.water)
    findings = [
        "In the simulated Trial 2 conditions the exceedances come almost entirely from the fish's pitch rate (and "
        f"some surge rate), while in the trials roll and yaw dominated (Tables 6.2/6.3: single tow roll "
        f"{fmt(min(r1))}–{fmt(max(r1))} %, yaw {fmt(min(y1))}–{fmt(max(y1))} % of the time). The illustrative fish is symmetric with no roll–yaw coupling, and the stern tow "
        "point on the centre line feels little lateral motion, so roll and yaw rates stay far below the limits.",
        f"The single tow's light fish streams at {fmt(depth_single)} m on the 20 m cable, which is nearly horizontal, so vertical "
        "tow-point motion reaches it as a transverse cable motion that drag attenuates; the two-part tow's depressor "
        "sits on a steep cable and passes heave on axially. Which tow is better then depends on the fish's pitch "
        "damping (sensitivity rows) and on the fish depth/cable angle — none of which the thesis gives.",
        f"The 41.2 kg fish is only {fmt(fish_wet)} N heavy in water and its cable carries little more than the "
        "fish's drag "
        f"({fmt(values['5.6kn/into/baseline']['single']['fish_cable_T_mean'])} N mean at 5.6 kn, single tow), so "
        "the cable at the fish goes slack intermittently "
        f"({fmt(values['5.6kn/into/baseline']['single']['fish_cable_slack_pct'])} % of the time into the swell) "
        "and re-tightens with a jerk: the spikes in the pitch rate (figure).",
    ]
    disagreements = []
    if not claims[0]["holds"]:
        disagreements.append(
            f"The trials' main result — the two-part tow cuts the time above the sonar limits by "
            f"{fmt(min(TRIAL_REDUCTION_PCT.values()))}–{fmt(max(TRIAL_REDUCTION_PCT.values()))} % — is NOT "
            "reproduced with the available inputs. The thesis prints no sea state, vessel, fish, depressor or cable "
            "data for the trials (Tables A3/A4 give lengths, direction to swell, wing and tow point only; the results "
            "Tables A5–A11 are withheld), so the comparison rests on assumed data whose effect is larger than the "
            "effect being tested: with the default fish damping the two-part fish pitches more; the observed "
            "exceedances were roll and yaw, which a symmetric fish behind a centre-line tow point hardly shows." +
            "".join(f" With the fish's rotational damping raised to 1.0, the two-part tow's reduction of 'any' is "
                    f"{v['reduction_pct']:+.0f} % ({k.split('/')[1]} the swell)." for k, v in values.items()
                    if k.endswith("fish damping 1.0") and v["reduction_pct"] is not None))
    tables = [
        Table("Simulated Trial 2 conditions: fish depth and % of time above each Table 6.1 limit (and above any), "
              "rms pitch rate, and the two-part tow's reduction of 'any' against the single tow",
              ["speed", "direction to swell", "variant", "tow", "fish depth (m)", "roll %", "pitch %", "yaw %",
               "surge %", "sway %", "heave %", "any %", "rms pitch rate (°/s)", "mean tension at the fish (N)",
               "fish cable slack (% time)", "reduction of 'any'"], rows,
              "Speeds read as knots (Table A4's unit is not stated). Limits: surge/sway/heave 1 m/s, roll and pitch "
              "6.28°/s, yaw 1.05°/s."),
        Table("The trials' measured averages (thesis Tables 6.2 and 6.3, % of samples above the limits)",
              ["trial / tow", "roll", "pitch", "yaw", "surge", "sway", "heave", "any"], ref_rows,
              "Reductions of 'any' quoted in the text: " + ", ".join(f"{k} {v:.1f} %" for k, v in
                                                                     TRIAL_REDUCTION_PCT.items()) + "."),
    ]
    figs = [_fig(recs, ctx.outdir)] if recs else []
    return {
        "key": "trials", "title": "Case 5 — Full-scale trials: single vs two-part tow (Tables A3/A4, 6.1–6.3)",
        "sources": [f"{THESIS}, §6.4, Tables 6.1–6.3, A3, A4 (Tables A5–A11 withheld)"],
        "inputs": [
            "Table A4, Trial 2 (Port Phillip Bay): single tows ST1-2…ST9-2 (20 m, no wing, forward tow point, "
            "5.5–8.6) and two-part tows TT1-2…TT9-2 (20 m primary + 10 m secondary, no wing, 4.7–7.9), with, across "
            "and into the swell; Table 6.1 rate limits.",
            f"Runs of {dur - t_skip:.0f} s after a {t_skip:.0f} s start-up, rates of the fish: time derivatives of "
            "surge/sway/heave about the mean path and body angular rates.",
        ],
        "assumptions": [
            "Sea: WMO sea state 3, coastal (fetch-limited) period, JONSWAP, short-crested (cos-2s, s = 10), one "
            "seed — the thesis records no sea state for either trial.",
            "Vessel: the `coastal_survey` preset (15 m, stern tow point), standing in for the RAN craft (docs/vessel.md).",
            "Fish: the 41.2 kg illustrative fish of Two-Part Tow 1; depressor: the 300 kg depressor; cables: the "
            "Chapter 4 primary (0.68-inch armoured) and secondary; the secondary hangs from the depressor's aft tow "
            "point (Tow 2 style; the trial's rig drawing is lost).",
            "Speeds in knots (5.6 kn = 2.88 m/s and 8.0 kn = 4.12 m/s, the two speed groups of Table A4).",
        ],
        "tables": [t.to_dict() for t in tables], "figures": [f.to_dict() for f in figs],
        "findings": findings, "disagreements": disagreements, "claims": claims, "values": values,
    }


def _fig(recs, outdir) -> Figure:
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(3, 1, figsize=(10, 7), sharex=True)
    for tow, col in (("single", "C3"), ("two-part", "C0")):
        r = recs[tow]
        rates = motion_rates(r, "fish")
        t = r.t - r.t[0]
        ax[0].plot(t, rates["heave"], color=col, lw=0.8, label=tow)
        ax[1].plot(t, np.degrees(rates["pitch"]), color=col, lw=0.8, label=tow)
        ax[2].plot(t, np.degrees(rates["yaw"]), color=col, lw=0.8, label=tow)
    for a, lim, lab in ((ax[0], 1.0, "heave rate (m/s)"), (ax[1], 6.28, "pitch rate (°/s)"),
                        (ax[2], 1.05, "yaw rate (°/s)")):
        a.axhline(lim, color="k", ls=":", lw=0.8)
        a.axhline(-lim, color="k", ls=":", lw=0.8)
        a.set_ylabel(lab)
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    ax[0].set_xlim(0, 120)
    ax[2].set_xlabel("time (s)")
    fig.suptitle("Trial 2 conditions, 5.6 kn into the swell: fish rates against the Table 6.1 limits (dotted)",
                 fontsize=10)
    return Figure(savefig(fig, outdir, "trials_rates.png"), "Fish heave, pitch and yaw rates, single vs two-part.")
