"""Reduced models of the Houbolt solver: the vertical-plane model (``solver.planar``) and bodies reduced to
surge/heave/pitch (``dof = "surge_heave_pitch"``).

* on a planar scene (no lateral excitation) the 3-D model stays exactly in the plane, and the reduced
  models reproduce it to round-off (same Newton iterations, relative differences ≤ 1e-9);
* the kernel's reduced step equals the numpy twin's;
* a reduced body in a 3-D scene with a lateral current holds its roll and yaw;
* scenes with lateral excitation are refused, naming the field.
"""
from __future__ import annotations

import numpy as np
import pytest

import towenv
from towenv.core import kernels as K
from towenv.verification import twin


def _reduced_bodies(scene):
    d = towenv.load_scene(scene).to_dict()
    for b in d["bodies"]:
        if b["kind"] in ("fish", "depressor"):
            b["dof"] = "surge_heave_pitch"
    return d


def _max_rel(a, b):
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(a)), 1e-30))


@pytest.mark.parametrize("scene", ["two_part_tow_1", "two_part_coastal_ss4"])
def test_planar_and_pitch_only_models_reproduce_the_3d_model_on_a_planar_scene(scene):
    """Surge/heave excitation only (two_part_tow_1), or head seas with a ship model and a compensator
    (two_part_coastal_ss4): the 3-D run keeps y and roll/yaw at round-off, and the planar and pitch-only
    runs take the same Newton iterations and agree with it to round-off (measured ≤ 4e-10 relative over
    60 s; bound 1e-9)."""
    full = towenv.Simulator(scene)
    plane = towenv.Simulator(scene, planar=True)
    pitch_only = towenv.Simulator(_reduced_bodies(scene))
    y0 = full.hist_r[0][full.system.top_node, 1]
    free = plane.system.node_kind == K.FREE
    y_free = plane.hist_r[0][free, 1].copy()
    for _ in range(30):
        for sim in (full, plane, pitch_only):
            sim.advance(2.0)
        assert np.max(np.abs(full.hist_r[0][:, 1] - y0)) < 1e-12
        assert np.max(np.abs(full.hist_ang[0][:, [0, 2]])) < 1e-12
        for sim in (plane, pitch_only):
            assert _max_rel(full.hist_r, sim.hist_r) < 1e-9
            assert _max_rel(full.tens_hist, sim.tens_hist) < 1e-9
            assert np.max(np.abs(full.hist_ang - sim.hist_ang)) < 1e-9 * max(np.max(np.abs(full.hist_ang)), 1e-3)
    assert np.array_equal(plane.hist_r[0][free, 1], y_free)      # free nodes held exactly, not to round-off
    assert np.all(plane.hist_ang[:, :, [0, 2]] == 0.0)
    assert full.stats["iterations"] == plane.stats["iterations"] == pitch_only.stats["iterations"]


@pytest.mark.parametrize("mode", ["planar", "pitch_only"])
def test_reduced_houbolt_step_matches_twin(mode):
    from twin_cases import EXCITATION, SCENES, _simulator, kernel_and_twin_step

    d = SCENES["two_part"](excitation=EXCITATION)
    if mode == "planar":
        d["solver"]["planar"] = True
        d["current"] = {"velocity": [0.1, 0.0, 0.05]}           # the twin tests' current without its y part
    else:
        for b in d["bodies"]:
            if b["kind"] in ("fish", "depressor"):
                b["dof"] = "surge_heave_pitch"
    sim = _simulator(d)
    sim.advance(2.0)
    kernel_and_twin_step(sim)


def test_pitch_only_body_holds_roll_and_yaw_in_a_lateral_current():
    """Two-part tow in a 0.3 m/s cross current: the 6-DOF bodies roll and yaw, the reduced ones keep the
    static roll (0) and yaw (along the relative flow) while surging, heaving and pitching."""
    cur = {"current": {"velocity": [0.0, 0.3, 0.0]}}
    d6 = towenv.load_scene("two_part_tow_1").with_overrides(**cur)
    dr = towenv.load_scene(_reduced_bodies("two_part_tow_1")).with_overrides(**cur)
    six, red = towenv.Simulator(d6), towenv.Simulator(dr)
    start = red.hist_ang[0].copy()
    six.advance(20.0)
    red.advance(20.0)
    assert np.max(np.abs(six.hist_ang[0][:, [0, 2]] - start[:, [0, 2]])) > 1e-4
    np.testing.assert_array_equal(red.hist_ang[:, :, [0, 2]], np.broadcast_to(start[:, [0, 2]], (3, 2, 2)))
    assert np.max(np.abs(red.hist_ang[0][:, 1] - start[:, 1])) > 1e-3          # pitch moves
    assert np.ptp(red.hist_r[:, :, 1]) > 0.0                                      # nodes still move laterally


@pytest.mark.parametrize("override, field", [
    ({"current": {"velocity": [1.0, 0.2, 0.0]}}, "current"),
    ({"vessel.excitation": [{"type": "sinusoid", "axis": "y", "amplitude": 1.0, "period": 6.0}]},
     "vessel.excitation[0].axis"),
    ({"vessel.heading_deg": 30.0}, "vessel.heading_deg"),
    ({"vessel.manoeuvres": [{"type": "turn", "start_time": 10.0, "radius": 25.0, "angle_deg": 180.0}]},
     "vessel.manoeuvres[0]"),
])
def test_planar_refuses_lateral_excitation(override, field):
    sc = towenv.load_scene("two_part_tow_1").with_overrides(**override)
    towenv.Simulator(sc)                      # the 3-D model takes it
    with pytest.raises(ValueError, match=r"^" + __import__("re").escape(field) + ".*solver.planar"):
        towenv.Simulator(sc, planar=True)


def test_planar_refuses_oblique_and_short_crested_seas_and_asymmetric_bodies():
    base = towenv.load_scene("two_part_coastal_ss4")
    with pytest.raises(ValueError, match=r"^sea.heading_deg"):
        towenv.Simulator(base.with_overrides(**{"sea.heading_deg": 135.0}), planar=True)
    with pytest.raises(ValueError, match=r"^sea.spreading_s"):
        towenv.Simulator(base.with_overrides(**{"sea.spreading_s": 10.0}), planar=True)
    towenv.Simulator(base.with_overrides(**{"sea.heading_deg": 0.0}), planar=True)      # following seas: fine
    d = towenv.load_scene("two_part_tow_1").to_dict()
    d["bodies"][0]["cg"] = [0.0, 0.05, -0.1]
    with pytest.raises(ValueError, match=r"^bodies\[.*\]\.cg: the lateral"):
        towenv.Simulator(d, planar=True)
    d = towenv.load_scene("two_part_tow_1").to_dict()
    rigid = next(b for b in d["bodies"] if b["kind"] in ("fish", "depressor"))
    inc = rigid["coefficients"]["incidence_deg"]
    rigid["horizontal_coefficients"] = {"incidence_deg": inc, "drag": rigid["coefficients"]["drag"],
                                        "lift": [0.1] * len(inc), "moment": [0.0] * len(inc)}
    with pytest.raises(ValueError, match=r"horizontal_coefficients: side force"):
        towenv.Simulator(d, planar=True)


def test_reduced_models_need_the_houbolt_solver():
    from towenv.core.explicit import ExplicitSimulator
    with pytest.raises(ValueError, match=r"^solver.planar: the reduced models exist for the houbolt solver"):
        ExplicitSimulator("two_part_tow_1", scheme="rk2", planar=True)
    with pytest.raises(ValueError, match=r"dof = 'surge_heave_pitch'"):
        ExplicitSimulator(_reduced_bodies("two_part_tow_1"), scheme="rk2")


def test_planar_refuses_a_tow_point_path_that_moves_sideways_at_run_time():
    """A sea set at run time with an oblique heading moves the tow point sideways: the planar simulator
    refuses to step it (ValueError naming solver.planar) rather than silently dropping the sway."""
    sim = towenv.Simulator("two_part_coastal_ss4", planar=True)
    sim.advance(1.0)
    sim.set_sea({"hs": 2.0, "tp": 8.0, "heading_deg": 120.0}, seed=3)
    with pytest.raises(ValueError, match=r"^solver.planar: the tow-point path moves laterally"):
        sim.advance(1.0)


def test_dof_field_is_validated():
    d = towenv.load_scene("two_part_tow_1").to_dict()
    d["bodies"][0]["dof"] = "heave_only"
    with pytest.raises(Exception, match="dof"):
        towenv.Simulator(d)
