"""Validation report (issue 6): the quick version of every case runs, and its qualitative claims hold.

The full report is `python scripts/validate.py` (docs/validation.md); CI runs the short versions here
(about 40 s in all) and checks the claims the simulator reproduces. Claims it does not reproduce are
reported in docs/validation.md with the reason, and are not asserted here."""
import json
import math

import pytest

pytestmark = pytest.mark.slow          # the quick validation report takes ~30 s

from towenv.scene import load_scene
from towenv.validation import report
from towenv.validation.common import amplitude, fmt, run_scene


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    """All quick cases, run once into a temporary folder (figures included)."""
    out = tmp_path_factory.mktemp("validation")
    data = report.run_cases(quick=True, outdir=out / "validation", progress=False, log=lambda *_: None)
    return data, out


def claim(case, start):
    hits = [c for c in case["claims"] if c["claim"].startswith(start)]
    assert hits, f"no claim starting {start!r} in {case['key']}: {[c['claim'] for c in case['claims']]}"
    return hits[0]


def test_every_case_ran_and_wrote_its_figures(quick):
    data, out = quick
    assert set(data["cases"]) == {"thesis", "channel", "hover", "srivastava", "trials", "problems"}
    for key, case in data["cases"].items():
        if key == "problems":
            continue
        for field in ("inputs", "assumptions", "tables", "figures", "findings", "claims"):
            assert case[field], f"{key}: empty {field}"
        for fig in case["figures"]:
            assert (out / fig["file"]).is_file(), fig["file"]
    assert data["meta"]["total_s"] < 240.0


# ---- case 1: thesis Chapter 4 -------------------------------------------------------------------
def test_two_part_tow_reduces_fish_heave_against_conventional(quick):
    case = quick[0]["cases"]["thesis"]
    c = claim(case, "Two-part tow reduces fish heave")
    assert c["holds"], c["evidence"]
    v = case["values"]
    assert v["fish_heave_tp1"] < 0.75 * v["fish_heave_conv"]          # at least 25 % less (measured ~48 %)
    assert v["fish_heave_tp1"] < v["depressor_heave_tp1"]               # the depressor takes the motion


def test_turns_bodies_cut_inside_and_deepen(quick):
    case = quick[0]["cases"]["thesis"]
    assert claim(case, "In the 180° turns every body tracks inside")["holds"]
    assert claim(case, "Every body deepens during the turn")["holds"]
    assert case["values"]["parallel_min_secondary_distance"] > 1.0     # the secondaries never touch


# ---- case 2: channel runs --------------------------------------------------------------------------
def test_channel_two_part_decouples_fish_from_depressor(quick):
    case = quick[0]["cases"]["channel"]
    assert claim(case, "Two-part tow decouples the fish from the depressor")["holds"]
    assert claim(case, "Ball depressor: its surge is much lower than its heave")["holds"]


def test_channel_sensitivity_table_covers_table_6_5(quick):
    case = quick[0]["cases"]["channel"]
    spread = case["values"]["spread"]
    assert len(spread) == 11                                             # the 11 rows of Table 6.5
    for key, s in spread.items():
        assert s["lo"] <= s["hi"] and s["table65_std"] > 0, key


# ---- case 3: Hover et al. -------------------------------------------------------------------------
def test_hover_frequency_response_quasi_static_and_closed_form(quick):
    case = quick[0]["cases"]["hover"]
    assert claim(case, "At low frequency the towfish follows the top heave")["holds"]
    c = claim(case, "While the cable stays taut, the time-domain heave response agrees")
    assert c["holds"], c["evidence"]


def test_hover_linearised_model_matches_time_domain_while_taut(quick):
    """towenv.linear on the same planar scene: heave and end tensions follow the time-domain sweep while the
    cable is taut (measured ≤ 2 %; the claim's threshold is the issue's 15 %), and the compensator cases by
    the stochastic linear model exist next to the time-domain ones."""
    case = quick[0]["cases"]["hover"]
    c = claim(case, "While the cable stays taut, the linearised model")
    assert c["holds"], c["evidence"]
    dev = case["values"]["linear"]["max_dev_taut_pct"]
    assert dev["Q"] < 5.0 and dev["T1"] < 5.0 and dev["Tn"] < 5.0
    lc = case["values"]["linear_compensator"]
    assert "SS5/b-tuned" in lc and lc["SS5/b-tuned"]["Q_13"] > 0


def test_hover_locked_compensator_transmits_more_heave_than_damping_tuned(quick):
    case = quick[0]["cases"]["hover"]
    c = claim(case, "A locked compensator transmits more fish heave than the damping-tuned one")
    assert c["holds"], c["evidence"]
    comp = case["values"]["compensator"]
    # the damping-tuned compensator keeps the stroke within the 4.0 m travel in SS5 (1/1000 level)
    assert comp["SS5/b-tuned"]["stats"]["R_1000_level"] < 4.0


def test_hover_preliminary_tuning_reproduces_the_printed_requirement(quick):
    case = quick[0]["cases"]["hover"]
    p6 = case["values"]["prelim"]["SS6"]
    assert p6["deck_h13"] == pytest.approx(5.25, rel=1e-6)
    assert p6["k-tuned"]["R"] == pytest.approx(0.41, abs=1e-3)
    assert p6["b-tuned"]["R"] == pytest.approx(0.41, abs=1e-3)
    # Hover's rule: a stiffness-tuned compensator above k_crit is worse than locking
    assert p6["k_tuned"] > p6["k_crit"]
    assert p6["k-tuned"]["p1"] > p6["locked"]["p1"] > p6["b-tuned"]["p1"]


def test_hover_s_shape_isolates_rov_heave(quick):
    case = quick[0]["cases"]["hover"]
    assert claim(case, "S-shape: ROV heave is down by 40 dB or more at 0.8 rad/s")["holds"]
    assert claim(case, "S-shape: no unloading of the cable at the ROV")["holds"]


# ---- case 4: Srivastava et al. --------------------------------------------------------------------
def test_speed_up_raises_the_array_and_the_tension(quick):
    case = quick[0]["cases"]["srivastava"]
    assert claim(case, "Accelerating 4 → 12 m/s makes the array rise")["holds"]
    assert claim(case, "Accelerating raises the tow-point tension")["holds"]
    assert claim(case, "Decelerating 12 → 4 m/s makes the array sink")["holds"]


def test_current_direction_orders_tension_and_depth(quick):
    case = quick[0]["cases"]["srivastava"]
    assert claim(case, "Towing against the current gives more tension")["holds"]
    assert claim(case, "A steady tow in a current equals a tow at the relative speed")["holds"]


def test_srivastava_scene_is_table_1():
    sc = load_scene("srivastava_towed_array")
    rho, g = sc.water.density, sc.water.gravity
    tow, arr, tail = sc.line("tow_cable"), sc.line("array"), sc.line("tail")
    assert arr.top.splice == "tow_cable" and tail.top.splice == "array"
    assert (tow.length, arr.length, tail.length) == (723.0, 274.32, 30.48)
    for ln, d, w, ct in ((tow, 0.0406, 2.3349, 0.015), (arr, 0.079375, 0.0, 0.00898), (tail, 0.0254, 0.569134, 0.02168)):
        assert ln.diameter == d
        assert ln.wet_weight_per_length(sc.water) == pytest.approx(w, abs=2e-3)
        assert ln.ct == pytest.approx(math.pi * ct, rel=1e-4)            # C_t on pi*d (the paper's q vector)
    assert rho == 1025.0 and g == pytest.approx(9.80665)


# ---- case 5: trials ---------------------------------------------------------------------------------
def test_trials_case_scores_both_tows(quick):
    case = quick[0]["cases"]["trials"]
    v = case["values"]["5.6kn/into/baseline"]
    for tow in ("single", "two-part"):
        assert 0.0 <= v[tow]["any"]["pct_over"] <= 100.0
        assert v[tow]["depth"] > 0
    # the two-part fish runs deeper (it hangs from the depressor)
    assert v["two-part"]["depth"] > v["single"]["depth"]


# ---- simulator problems -------------------------------------------------------------------------------
def test_problem_reproductions_run(quick):
    items = quick[0]["cases"]["problems"]["items"]
    assert len(items) >= 2
    assert all(it["text"] for it in items)


def test_reverse_flow_body_drag_is_continuous(quick):
    """Fixed: reverse flow beyond a ±90° table is folded fore-aft instead of clipped (kernels.py)."""
    v = quick[0]["cases"]["problems"]["items"][0]["values"]
    assert v["drag_reverse"] == pytest.approx(v["drag_forward"], rel=0.01)


# ---- report -------------------------------------------------------------------------------------------
def test_report_renders_from_the_cache(quick, tmp_path):
    data, _ = quick
    cache = report.save_cache(data, tmp_path / "validation" / "results.json")
    text = report.render(report.load_cache(cache), tmp_path / "validation.md")
    for case in data["cases"].values():
        assert case["title"] in text
    assert "QUICK MODE" in text
    assert "nan" not in text.lower().replace("nanc", "")
    assert text.count("![") == sum(len(c.get("figures", [])) for c in data["cases"].values())
    json.dumps(data)                                                      # the cache is plain JSON


def test_helpers():
    import numpy as np
    t = np.linspace(0, 20, 2001)
    assert amplitude(t, 0.3 * np.sin(2 * t + 0.4) + 5.0, 2.0) == pytest.approx(0.3, rel=1e-6)
    assert fmt(0.0) == "0" and fmt(1234.5) == "1234" and fmt(0.01234) == "0.0123"
    out = run_scene({**load_scene("peer_deck").to_dict(), "solver": {"dt": 0.05}}, 1.0)
    assert out.ok and out.result.t[-1] == pytest.approx(1.0)
