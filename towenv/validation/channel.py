"""Case 2: the thesis's scaled-model channel runs I31, C31 and YA22 (Table 6.4, Table A1) with the body
properties the thesis does not print estimated, and the sensitivity of the results to every estimate,
set against the thesis's own model-vs-experiment spread (Table 6.5)."""
from __future__ import annotations

import copy
import math

import numpy as np

from ..scene import load_scene
from .common import CaseContext, Figure, Table, amplitude, fmt, run_scene, savefig
from .reference import TABLE_6_5, THESIS

PERIOD = 3.5
RUNS = ("I31", "C31", "YA22")
# quantities compared in Table 6.5, per run: (body, motion)
QUANTITIES = {
    "I31": [("fish", "pitch"), ("fish", "heave"), ("fish", "surge")],
    "C31": [("fish", "pitch"), ("fish", "heave"), ("fish", "surge"), ("depressor", "pitch"),
            ("depressor", "heave"), ("depressor", "surge")],
    "YA22": [("fish", "yaw"), ("fish", "sway")],
}
EXTRA = {"I31": [("depressor", "heave"), ("depressor", "surge")], "C31": [],
         "YA22": [("depressor", "sway"), ("depressor", "yaw")]}


def _signal(res, body, motion):
    b = res.bodies[body]
    if motion in ("surge", "sway", "heave"):
        return b[motion]
    return np.degrees(b["euler"][:, {"roll": 0, "pitch": 1, "yaw": 2}[motion]])


def _body(d, name):
    return next(b for b in d["bodies"] if b["name"] == name)


def _scale_col(d, body, table, col, f):
    b = _body(d, body)
    if b.get(table) is None:
        return
    b[table][col] = [f * x for x in b[table][col]]


def _fish_wet(d, frac):
    b = _body(d, "fish")
    b["volume"] = b["mass"] * (1.0 - frac) / d["water"]["density"]


def _set_phase(d, deg):
    for e in d["vessel"]["excitation"]:
        if e["axis"] == "z":
            e["phase_deg"] = deg


def _variants(quick):
    """(label, group, runs it applies to, function editing a scene dict in place)."""
    def cab(**kw):
        def f(d):
            for ln in d["lines"]:
                for k, v in kw.items():
                    ln[k] = v(ln[k]) if callable(v) else v
        return f

    def each(*fs):
        def f(d):
            for g in fs:
                g(d)
        return f

    all3 = RUNS
    v = [
        ("cable EA 1e4 N (×0.2)", "cable", all3, cab(EA=1.0e4)),
        ("cable EA 2.5e5 N (×5)", "cable", all3, cab(EA=2.5e5)),
        ("cable 'inertia coefficients' read as C_m = 1 + C_a (C_an 0, C_at 0)", "cable", all3, cab(can=0.0, cat=0.0)),
        ("cable mass ×1.5 (heavier than water)", "cable", all3, cab(mass_per_length=lambda m: 1.5 * m)),
        ("X–Z in phase (0°)", "excitation", ("I31", "C31"), lambda d: _set_phase(d, 0.0)),
        ("Z lags X by 90°", "excitation", ("I31", "C31"), lambda d: _set_phase(d, -90.0)),
        ("fish wet weight 0.5 % of its weight", "fish", all3, lambda d: _fish_wet(d, 0.005)),
        ("fish wet weight 5 % of its weight", "fish", all3, lambda d: _fish_wet(d, 0.05)),
        ("fish added mass and inertia ×0.5", "fish", all3,
         lambda d: _body(d, "fish").update(added_mass=[0.5 * x for x in _body(d, "fish")["added_mass"]],
                                           added_inertia=[0.5 * x for x in _body(d, "fish")["added_inertia"]])),
        ("fish added mass and inertia ×1.5", "fish", all3,
         lambda d: _body(d, "fish").update(added_mass=[1.5 * x for x in _body(d, "fish")["added_mass"]],
                                           added_inertia=[1.5 * x for x in _body(d, "fish")["added_inertia"]])),
        ("fish inertia ×2", "fish", all3,
         lambda d: _body(d, "fish").update(inertia=[2 * x for x in _body(d, "fish")["inertia"]])),
        ("fish weathervane moment ×0.5", "fish", all3, lambda d: _scale_col(d, "fish", "coefficients", "moment", 0.5)),
        ("fish weathervane moment ×2", "fish", all3, lambda d: _scale_col(d, "fish", "coefficients", "moment", 2.0)),
        ("fish lift/side force ×0.5", "fish", all3, lambda d: _scale_col(d, "fish", "coefficients", "lift", 0.5)),
        ("fish lift/side force ×1.5", "fish", all3, lambda d: _scale_col(d, "fish", "coefficients", "lift", 1.5)),
        ("fish drag ×0.7", "fish", all3, lambda d: _scale_col(d, "fish", "coefficients", "drag", 0.7)),
        ("fish drag ×1.3", "fish", all3, lambda d: _scale_col(d, "fish", "coefficients", "drag", 1.3)),
        ("fish rotational damping ×0.2", "fish", all3,
         lambda d: _body(d, "fish").update(rotational_damping=[0.02] * 3, quadratic_rotational_damping=[0.1] * 3)),
        ("fish rotational damping ×5", "fish", all3,
         lambda d: _body(d, "fish").update(rotational_damping=[0.5] * 3, quadratic_rotational_damping=[2.5] * 3)),
        ("ball drag coefficient 1.0 (C_d 0.47 assumed)", "depressor", ("I31",),
         lambda d: _body(d, "depressor").update(drag_area=_body(d, "depressor")["drag_area"] / 0.47)),
        ("ball wet weight ×2 (same size, denser)", "depressor", ("I31",),
         lambda d: _body(d, "depressor").update(
             mass=_body(d, "depressor")["mass"] + (_body(d, "depressor")["mass"]
                                                   - d["water"]["density"] * _body(d, "depressor")["volume"]))),
        ("depressor mass 11.1 kg (geometric 1/27 scale)", "depressor", ("C31", "YA22"),
         lambda d: _body(d, "depressor").update(mass=300.0 / 27.0)),
        ("depressor lift ×0.7", "depressor", ("C31", "YA22"),
         lambda d: _scale_col(d, "depressor", "coefficients", "lift", 0.7)),
        ("depressor lift ×1.3", "depressor", ("C31", "YA22"),
         lambda d: _scale_col(d, "depressor", "coefficients", "lift", 1.3)),
        ("depressor moments ×2", "depressor", ("C31", "YA22"),
         lambda d: (_scale_col(d, "depressor", "coefficients", "moment", 2.0),
                    _scale_col(d, "depressor", "horizontal_coefficients", "moment", 2.0))),
        ("Δt = 0.0005 s (numerical check)", "numerics", all3, lambda d: d["solver"].update(dt=0.0005)),
    ]
    if quick:
        keep = {"cable EA 1e4 N (×0.2)", "X–Z in phase (0°)", "fish weathervane moment ×2"}
        v = [x for x in v if x[0] in keep]
    return v


def _measure(res, run):
    w = res.window(res.t[-1] - 6 * PERIOD + 1e-9) if res.t[-1] > 10 * PERIOD else res.window(res.t[-1] - 3 * PERIOD + 1e-9)
    om = 2 * math.pi / PERIOD
    out, sig = {}, {}
    for body, motion in QUANTITIES[run] + EXTRA[run]:
        x = _signal(w, body, motion)
        out[(body, motion)] = amplitude(w.t, x, om)
        sig[(body, motion)] = x - x.mean()
    out[("top", "tension_mean")] = float(w.top_tension.mean())
    out[("top", "tension_amp")] = amplitude(w.t, w.top_tension, om)
    return out, sig, w


def run(ctx: CaseContext) -> dict:
    quick = ctx.quick
    dur = 6 * PERIOD if quick else 12 * PERIOD
    variants = _variants(quick)
    n_runs = len(RUNS) + sum(len(v[2]) for v in variants) + (0 if quick else 8)
    bar = ctx.bar(n_runs, "channel runs")
    base, base_sig, base_w, scenes = {}, {}, {}, {}
    for run_id in RUNS:
        d = load_scene(f"channel_{run_id}").to_dict()
        scenes[run_id] = d
        out = run_scene(d, dur, record_interval=0.01)
        bar.step(run_id)
        if not out.ok:
            raise RuntimeError(f"channel_{run_id} diverged: {out.error}")
        base[run_id], base_sig[run_id], base_w[run_id] = _measure(out.result, run_id)

    # ---- sensitivity -------------------------------------------------------------------------
    sens = {}            # (run, body, motion) -> list of (label, group, d_amp_pct, std_diff_pct)
    failures = []
    for label, group, runs, edit in variants:
        for run_id in runs:
            d = copy.deepcopy(scenes[run_id])
            edit(d)
            out = run_scene(d, dur, record_interval=0.01)
            bar.step(f"{run_id} {label[:20]}")
            if not out.ok:
                failures.append(f"{run_id} / {label}: {out.error}")
                continue
            m, sig, _ = _measure(out.result, run_id)
            for q in QUANTITIES[run_id]:
                a0 = base[run_id][q]
                n = min(len(sig[q]), len(base_sig[run_id][q]))
                diff = sig[q][:n] - base_sig[run_id][q][:n]
                sens.setdefault((run_id,) + q, []).append(
                    (label, group, 100 * (m[q] / a0 - 1), 100 * float(np.std(diff)) / a0))

    # ---- period sweep and single- vs two-part (Table A1 runs) ---------------------------------
    sweep = {}
    yy = None
    if not quick:
        for cfg, scene in (("C", "channel_C31"), ("I", "channel_I31")):
            for k, per in ((1, 3.5), (2, 2.5), (3, 1.5)):
                d = load_scene(scene).to_dict()
                for e in d["vessel"]["excitation"]:
                    e["period"] = per
                d["vessel"]["ramp"] = {"type": "half_cosine", "duration": 2 * per}
                out = run_scene(d, max(12 * per, 30.0), record_interval=0.005)
                bar.step(f"{cfg}3{k}")
                w = out.result.window(out.result.t[-1] - 6 * per + 1e-9)
                om = 2 * math.pi / per
                sweep[(cfg, per)] = {(b, mo): amplitude(w.t, _signal(w, b, mo), om)
                                     for b in ("fish", "depressor") for mo in ("surge", "heave", "pitch")
                                     if not (b == "depressor" and cfg == "I" and mo == "pitch")}
        # YY22: single-part tow of the model fish on the 1.5 m cable, Y 0.15 m at 3.5 s (Table A1)
        d = copy.deepcopy(scenes["YA22"])
        prim = d["lines"][0]
        prim.update(segments=8, bottom={"body": "fish"})
        d["lines"] = [prim]
        d["bodies"] = [b for b in d["bodies"] if b["name"] == "fish"]
        d["name"] = "channel_YY22"
        out = run_scene(d, dur, record_interval=0.01)
        bar.step("YY22")
        w = out.result.window(out.result.t[-1] - 6 * PERIOD + 1e-9)
        om = 2 * math.pi / PERIOD
        yy = {mo: amplitude(w.t, _signal(w, "fish", mo), om) for mo in ("sway", "yaw")}
        yy["depth"] = float(-w.bodies["fish"]["position"][:, 2].mean())
    bar.close()

    # ---- tables -------------------------------------------------------------------------------
    base_rows = []
    for run_id in RUNS:
        for q in QUANTITIES[run_id] + EXTRA[run_id]:
            unit = "°" if q[1] in ("pitch", "yaw", "roll") else "cm"
            val = base[run_id][q] * (1 if unit == "°" else 100)
            t65 = TABLE_6_5.get((run_id,) + q)
            base_rows.append([run_id, q[0], q[1], f"{fmt(val)} {unit}",
                              f"{t65[0]:+.2f} ± {t65[1]:.2f} %" if t65 else "(not in Table 6.5)"])
        base_rows.append([run_id, "top", "tension mean / amplitude",
                          f"{fmt(base[run_id][('top', 'tension_mean')])} / {fmt(base[run_id][('top', 'tension_amp')])} N",
                          "—"])

    summary_rows, values = [], {"base": {}, "spread": {}}
    for key, lst in sens.items():
        run_id, body, motion = key
        t65 = TABLE_6_5[key]
        d_amp = [x[2] for x in lst]
        lo, hi = min(d_amp), max(d_amp)
        worst = max(lst, key=lambda x: abs(x[2]))
        phys = [x for x in lst if x[1] != "numerics"]
        rss = math.sqrt(sum(x[2] ** 2 for x in phys))
        std_max = max(x[3] for x in phys)
        summary_rows.append([run_id, f"{body} {motion}", f"{lo:+.0f} … {hi:+.0f} %", f"{worst[0]} ({worst[2]:+.0f} %)",
                             f"{rss:.0f} %", f"{std_max:.0f} %", f"{t65[0]:+.1f} ± {t65[1]:.1f} %",
                             "larger" if max(abs(lo), abs(hi)) > t65[1] else "within"])
        values["spread"]["/".join(key)] = {"lo": lo, "hi": hi, "rss": rss, "table65_std": t65[1]}
    for run_id in RUNS:
        for q in QUANTITIES[run_id] + EXTRA[run_id]:
            values["base"]["/".join((run_id,) + q)] = base[run_id][q]

    detail_rows = []
    for label, group, runs, _ in variants:
        row = [label]
        for run_id in RUNS:
            for q in QUANTITIES[run_id]:
                hit = [x for x in sens.get((run_id,) + q, []) if x[0] == label]
                row.append(f"{hit[0][2]:+.0f}" if hit else "")
        detail_rows.append(row)
    detail_cols = ["variant"] + [f"{r} {b[0]}{'' if b == 'fish' else 'ep'}. {m}" if False else f"{r} {b} {m}"
                                 for r in RUNS for b, m in QUANTITIES[r]]

    tables = [
        Table("Baseline (embedded scenes): amplitude of the 3.5 s fundamental over the last periods, and the "
              "thesis's model-vs-experiment difference for that quantity (Table 6.5, mean ± std, % of amplitude)",
              ["run", "body", "motion", "simulated amplitude", "thesis Table 6.5 (sim − exp)"], base_rows,
              "The experimental amplitudes (Table A2) are withheld from the seed copy, so the simulated amplitudes "
              "cannot be compared with the experiment directly; Table 6.5 only says how far the thesis's own model "
              "was from it."),
        Table("Sensitivity to the estimated inputs: change of each Table 6.5 amplitude over all variants, the "
              "largest single contributor, the root-sum-square of the physical variants, the largest time-history "
              "discrepancy (std of variant − baseline, % of amplitude: the Table 6.5 metric) and the thesis's spread",
              ["run", "quantity", "range of Δ amplitude", "largest contributor", "RSS of Δ", "max std of Δ(t)",
               "Table 6.5 (sim − exp)", "spread vs Table 6.5 std"], summary_rows),
        Table("Every variant: change of each amplitude (%) against the baseline", detail_cols, detail_rows),
    ]
    claims = []
    findings = []
    c31 = base["C31"]
    claims.append({"claim": "Two-part tow decouples the fish from the depressor in heave (C31: fish heave < "
                            "depressor heave, §6.3.1, L5729)",
                   "holds": c31[("fish", "heave")] < c31[("depressor", "heave")],
                   "evidence": f"fish {fmt(100 * c31[('fish', 'heave')])} cm vs depressor "
                               f"{fmt(100 * c31[('depressor', 'heave')])} cm"})
    i31 = base["I31"]
    claims.append({"claim": "Ball depressor: its surge is much lower than its heave (L5735)",
                   "holds": i31[("depressor", "surge")] < i31[("depressor", "heave")],
                   "evidence": f"surge {fmt(100 * i31[('depressor', 'surge')])} cm, heave "
                               f"{fmt(100 * i31[('depressor', 'heave')])} cm"})
    claims.append({"claim": "Ball depressor: the towed fish's surge is slightly higher than the ball's (L5737)",
                   "holds": i31[("fish", "surge")] > i31[("depressor", "surge")],
                   "evidence": f"fish {fmt(100 * i31[('fish', 'surge')])} cm vs ball "
                               f"{fmt(100 * i31[('depressor', 'surge')])} cm"})
    sweep_rows = []
    if sweep:
        for cfg in ("C", "I"):
            for per in (3.5, 2.5, 1.5):
                s = sweep[(cfg, per)]
                sweep_rows.append([f"{cfg}3{[3.5, 2.5, 1.5].index(per) + 1}", per,
                                   100 * s[("depressor", "surge")], 100 * s[("depressor", "heave")],
                                   s.get(("depressor", "pitch")), 100 * s[("fish", "surge")],
                                   100 * s[("fish", "heave")], s[("fish", "pitch")]])
        C = {p: sweep[("C", p)] for p in (3.5, 2.5, 1.5)}
        I_ = {p: sweep[("I", p)] for p in (3.5, 2.5, 1.5)}
        claims += [
            {"claim": "Depressor fish (C31–C33): as the frequency rises its surge falls (L5733)",
             "holds": C[1.5][("depressor", "surge")] < C[3.5][("depressor", "surge")],
             "evidence": f"{fmt(100 * C[3.5][('depressor', 'surge')])} → {fmt(100 * C[1.5][('depressor', 'surge')])} cm"},
            {"claim": "Depressor fish (C31–C33): as the frequency rises its heave and pitch increase (L5733)",
             "holds": (C[1.5][("depressor", "heave")] > C[3.5][("depressor", "heave")]
                       and C[1.5][("depressor", "pitch")] > C[3.5][("depressor", "pitch")]),
             "evidence": f"heave {fmt(100 * C[3.5][('depressor', 'heave')])} → {fmt(100 * C[1.5][('depressor', 'heave')])} cm, "
                         f"pitch {fmt(C[3.5][('depressor', 'pitch')])} → {fmt(C[1.5][('depressor', 'pitch')])}°"},
            {"claim": "At high frequency the towed fish's heave falls (decoupling, L5737), both depressor types",
             "holds": (C[1.5][("fish", "heave")] < C[3.5][("fish", "heave")]
                       and I_[1.5][("fish", "heave")] < I_[3.5][("fish", "heave")]),
             "evidence": f"C: {fmt(100 * C[3.5][('fish', 'heave')])} → {fmt(100 * C[1.5][('fish', 'heave')])} cm; "
                         f"I: {fmt(100 * I_[3.5][('fish', 'heave')])} → {fmt(100 * I_[1.5][('fish', 'heave')])} cm"},
            {"claim": "Fish response better than the depressor's, especially at high frequency (L5729)",
             "holds": all(sweep[(c, p)][("fish", "heave")] < sweep[(c, p)][("depressor", "heave")]
                          for c in ("C", "I") for p in (3.5, 2.5, 1.5)),
             "evidence": "fish heave < depressor heave at every period of both configurations (sweep table)"},
        ]
        ya = base["YA22"]
        claims.append({"claim": "Under sway excitation the two-part tow (YA22) reduces the fish's sway and yaw "
                                "against the single-part tow (YY22) substantially (Figs 6.34/6.36, L6051)",
                       "holds": ya[("fish", "sway")] < yy["sway"] and ya[("fish", "yaw")] < yy["yaw"],
                       "evidence": f"sway {fmt(100 * ya[('fish', 'sway')])} vs {fmt(100 * yy['sway'])} cm, yaw "
                                   f"{fmt(ya[('fish', 'yaw')])} vs {fmt(yy['yaw'])}° (YY22 fish runs "
                                   f"{fmt(yy['depth'])} m deep)"})
        tables.append(Table("Period sweep (Table A1 runs C31–C33 and I31–I33: X 0.035 m, Z 0.1 m): fundamental "
                            "amplitudes (cm, °)",
                            ["run", "period (s)", "depressor surge", "depressor heave", "depressor pitch",
                             "fish surge", "fish heave", "fish pitch"], sweep_rows))
        values["sweep"] = {f"{c}{p}": {"/".join(k): v for k, v in s.items()} for (c, p), s in sweep.items()}
        values["YY22"] = yy

    larger = [r for r in summary_rows if r[-1] == "larger"]
    findings.append(f"{len(larger)} of {len(summary_rows)} Table 6.5 quantities move by more than the thesis's "
                    "model-vs-experiment standard deviation when a single estimated input is changed within a "
                    "plausible range; the estimates, not the solver, dominate the uncertainty of this comparison.")
    big = sorted(summary_rows, key=lambda r: -float(r[4].rstrip(" %")))[:3]
    findings.append("Largest RSS sensitivities: " + "; ".join(f"{r[0]} {r[1]} ({r[4]}, mostly {r[3]})" for r in big)
                    + ".")
    num = [x for lst in sens.values() for x in lst if x[1] == "numerics"]
    if num:
        findings.append(f"Halving Δt to 0.0005 s changes the amplitudes by at most {max(abs(x[2]) for x in num):.1f} %: "
                        "the numerical error is far below the input uncertainty.")
    disagreements = [
        "No direct comparison with the experiments is possible: Table A2 (measured amplitudes) is withheld and "
        "the thesis prints no body mass, size, inertia, added mass or coefficient for the models. What can be "
        "checked are the thesis's qualitative statements about the channel runs (claims table) and whether the "
        "estimated inputs could be pinned down by Table 6.5 (they cannot: see the sensitivity table)."]
    for c in claims:
        if not c["holds"]:
            why = ""
            if c["claim"].startswith("Under sway excitation") and yy is not None:
                ya = base["YA22"]
                why = (f" Here the depressor fish itself sways {fmt(100 * ya[('depressor', 'sway')])} cm and yaws "
                       f"{fmt(ya[('depressor', 'yaw')])}° under the {fmt(100 * 0.15)} cm excitation: its illustrative "
                       "horizontal table stops at 25° of sideslip and gives little lateral damping, whereas the thesis "
                       "credits the real depressor fish's large hydrodynamic forces with damping the lateral motion "
                       f"(L6176). The single-part fish runs only {fmt(yy['depth'])} m deep on a nearly horizontal "
                       "cable. Both are consequences of the estimated body data.")
            elif c["claim"].startswith("Ball depressor: the towed fish's surge"):
                why = (" The ball's surge here follows from the Z excitation acting through the inclined primary "
                       "(with the assumed 90° X–Z phase); the X–Z phase variant changes the I31 fish surge by up to "
                       f"{max(abs(x[2]) for x in sens.get(('I31', 'fish', 'surge'), [('', '', 0.0, 0.0)]) if x[1] == 'excitation'):.0f} %.")
            disagreements.append(f"Not reproduced: {c['claim']} — {c['evidence']}.{why}")
    if failures:
        disagreements.append("Variant runs that diverged: " + "; ".join(failures))

    figs = [_fig_runs(base_w, ctx.outdir), _fig_sens(sens, ctx.outdir)]
    if sweep:
        figs.append(_fig_sweep(sweep, ctx.outdir))
    return {
        "key": "channel", "title": "Case 2 — Thesis Chapter 6: channel runs I31, C31, YA22 (Tables 6.4, A1, 6.5)",
        "sources": [f"{THESIS}, §6.2–6.6, Tables 6.4, 6.5, A1 (Table A2 and Figs 6.64–6.83 withheld/lost)"],
        "inputs": [
            "Table 6.4: primary 1.5 m [6 + 2 segments], junction 0.25 m above the depressor, secondary 0.8 m "
            "(5 segments); cable D 2.2 mm, 3.013 g/m, C_t 0.2, C_n 1.2, inertia coefficients 0.1/1.0; Δt 0.001 s, "
            "1 N tolerance; 1 m/s fresh-water flow; X 0.035 m, Z 0.1 m at 3.5 s (I31, C31); YA22 Y 0.15 m at "
            "3.5 s (Table A1, erratum E24).",
            f"Embedded scenes `channel_I31`, `channel_C31`, `channel_YA22`; {dur:.0f} s runs, amplitudes from the "
            "last periods.",
        ],
        "assumptions": [
            "Every body property is estimated (docs/scenes.md): the model fish is the 41.2 kg fish scaled 1:3 "
            "(1.53 kg, 2 % heavy); the depressor fish is the 300 kg depressor at 1:3 with 5.45 kg mass (chosen "
            "for the full-scale cable angle); the ball is a steel sphere of the same wet weight (C_d 0.47, C_a 0.5).",
            "Coefficient tables are the illustrative full-scale ones (the thesis measured the models' on a "
            "planar-motion mechanism, but the results are in lost figures).",
            "Cable EA 5e4 N (not given); 'inertia coefficients' read as added-mass coefficients; the printed cable "
            "mass (buoyant in fresh water) is kept; X–Z phase 90° (not stated); the flow is a −1 m/s current.",
            "Each assumption is varied one at a time by the amounts in the variant table; Δt is halved as a "
            "numerical check.",
        ],
        "tables": [t.to_dict() for t in tables], "figures": [f.to_dict() for f in figs],
        "findings": findings, "disagreements": disagreements, "claims": claims, "values": values,
    }


# -------------------------------------------------------------------------------------------------
def _fig_runs(base_w, outdir) -> Figure:
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(4, 3, figsize=(14, 10))
    specs = {
        "I31": [("pitch", [("fish", "pitch")], "°"), ("heave", [("fish", "heave"), ("depressor", "heave")], "cm"),
                ("surge", [("fish", "surge"), ("depressor", "surge")], "cm")],
        "C31": [("pitch", [("fish", "pitch"), ("depressor", "pitch")], "°"),
                ("heave", [("fish", "heave"), ("depressor", "heave")], "cm"),
                ("surge", [("fish", "surge"), ("depressor", "surge")], "cm")],
        "YA22": [("yaw", [("fish", "yaw"), ("depressor", "yaw")], "°"),
                 ("sway", [("fish", "sway"), ("depressor", "sway")], "cm"),
                 ("roll", [("fish", "roll"), ("depressor", "roll")], "°")],
    }
    for j, run_id in enumerate(RUNS):
        w = base_w[run_id]
        t = w.t - w.t[0]
        for i, (lab, items, unit) in enumerate(specs[run_id]):
            for body, mo in items:
                x = _signal(w, body, mo)
                x = (x - x.mean()) * (100 if unit == "cm" else 1)
                ax[i, j].plot(t, x, label=body, color="C0" if body == "fish" else "C2")
            ax[i, j].set_ylabel(f"{lab} ({unit})")
            ax[i, j].legend(fontsize=7, loc="upper right")
            ax[i, j].grid(alpha=0.3)
        ax[3, j].plot(t, w.top_tension, color="C3")
        ax[3, j].set_ylabel("top tension (N)")
        ax[3, j].set_xlabel("time in the analysis window (s)")
        ax[3, j].grid(alpha=0.3)
        ax[0, j].set_title(f"{run_id} ({'ball' if run_id == 'I31' else 'depressor fish'}"
                           f"{', Y excitation' if run_id == 'YA22' else ''})", fontsize=10)
    fig.suptitle("Channel runs, baseline estimates: motions about the mean (cf. thesis Figs 6.64–6.83)", fontsize=11)
    return Figure(savefig(fig, outdir, "ch6_channel_runs.png"),
                  "Simulated channel runs I31, C31, YA22 with the estimated model properties.")


def _fig_sens(sens, outdir) -> Figure:
    import matplotlib.pyplot as plt
    keys = list(sens.keys())
    fig, ax = plt.subplots(figsize=(10, 0.55 * len(keys) + 1.5))
    groups = {"cable": "C0", "excitation": "C1", "fish": "C2", "depressor": "C4", "numerics": "0.5"}
    for i, k in enumerate(keys):
        t65 = TABLE_6_5[k]
        ax.add_patch(plt.Rectangle((-t65[1], i - 0.4), 2 * t65[1], 0.8, color="0.88", zorder=0))
        for lab, grp, d, _ in sens[k]:
            ax.plot(d, i, "o", ms=4, color=groups[grp], alpha=0.8)
    for g, c in groups.items():
        ax.plot([], [], "o", color=c, label=f"{g} variants")
    ax.add_patch(plt.Rectangle((0, 0), 0, 0, color="0.88", label="± Table 6.5 std (thesis sim − exp)"))
    ax.set_yticks(range(len(keys)))
    ax.set_yticklabels([f"{k[0]} {k[1]} {k[2]}" for k in keys], fontsize=8)
    ax.axvline(0, color="k", lw=0.8)
    ax.set_xlabel("change of amplitude against the baseline (%)")
    ax.grid(axis="x", alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=6, frameon=False)
    ax.set_title("Sensitivity of the channel-run amplitudes to the estimated inputs", fontsize=10)
    hi = max(d for v in sens.values() for _, _, d, _ in v)
    ax.set_xlim(-100.0, max(60.0, hi * 1.05 + 5.0))
    return Figure(savefig(fig, outdir, "ch6_sensitivity.png"),
                  "Each dot is one variant (one estimated input changed); grey band: the thesis's own "
                  "model-vs-experiment standard deviation (Table 6.5).")


def _fig_sweep(sweep, outdir) -> Figure:
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(12, 4))
    pers = [3.5, 2.5, 1.5]
    for j, cfg in enumerate(("C", "I")):
        for k, (b, mo, st) in enumerate((("depressor", "surge", "--"), ("depressor", "heave", "--"),
                                         ("depressor", "pitch", "--"), ("fish", "surge", "-"),
                                         ("fish", "heave", "-"), ("fish", "pitch", "-"))):
            vals = [sweep[(cfg, p)].get((b, mo)) for p in pers]
            if vals[0] is None:
                continue
            scale = 1 if mo == "pitch" else 100
            ax[j].plot(pers, [v * scale for v in vals], st, marker="o", color=f"C{k % 3}",
                       label=f"{b} {mo} ({'°' if mo == 'pitch' else 'cm'})")
        ax[j].set_xlabel("period (s)")
        ax[j].set_title(f"{cfg}31–{cfg}33 ({'depressor fish' if cfg == 'C' else 'ball depressor'})", fontsize=10)
        ax[j].legend(fontsize=7)
        ax[j].grid(alpha=0.3)
    fig.suptitle("Amplitude against excitation period (cf. thesis Figs 6.10, 6.14; the data of Table A2 are withheld)",
                 fontsize=10)
    return Figure(savefig(fig, outdir, "ch6_period_sweep.png"), "Channel period sweep, simulated.")
