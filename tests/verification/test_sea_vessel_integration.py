"""Irregular seas through the vessel to the tow point, with the compensator and winch (issue 3)."""
import numpy as np
import pytest

import towenv
from towenv.sea import SeaState


def test_coastal_scene_runs_with_statistics_from_one_command(tmp_path):
    """The issue's 'done means' scene: two-part tow, 3 m/s, coastal sea state 4 head seas, small craft,
    passive compensator — fish heave/pitch statistics and actuator histories from one simulate call."""
    res = towenv.simulate("two_part_coastal_ss4", duration=120.0)
    w = res.window(40.0)
    heave = 2 * np.std(w.bodies["fish"]["heave"])
    pitch = 2 * np.std(w.bodies["fish"]["euler"][:, 1])
    assert 0.05 < heave < 5.0 and 0.0 < pitch < 0.6
    assert np.ptp(w.actuators["stroke"]) > 0.01          # the compensator works
    assert np.all(np.abs(w.actuators["stroke"]) <= 1.0 + 1e-9)
    back = towenv.Result.load(res.save(tmp_path / "r"))
    np.testing.assert_array_equal(back.actuators["stroke"], res.actuators["stroke"])


def test_sea_seed_determinism_and_difference():
    a = towenv.Simulator("two_part_coastal_ss4", dt=0.1)
    b = towenv.Simulator("two_part_coastal_ss4", dt=0.1)
    a.advance(30.0)
    b.advance(30.0)
    assert np.array_equal(a.positions, b.positions)
    b.set_sea(SeaState(1.0, 5.0), seed=1)
    b.reset()
    b.advance(30.0)
    assert not np.array_equal(a.positions, b.positions)


def test_tow_point_heave_follows_the_vessel_rao_spectrum():
    """The tow-point vertical motion synthesised for the scene has the variance the vessel's tow-point
    RAO predicts for the sea (linear superposition in the frequency domain), within 10 % over a
    30-minute record (the sampling variability of a 200-component record is a few %)."""
    from towenv.vessel import response_moments
    sim = towenv.Simulator("two_part_coastal_ss4", dt=0.1)
    t = np.arange(0.0, 1800.0, 0.1) + 100.0
    z = sim.vessel_motion.offset(t)[:, 2]
    sea = sim.scene.sea.sea_state()
    m = response_moments(sea, "coastal_survey", speed=sim.path.initial_speed)
    m0 = m["tow_point"][0][2]
    assert np.var(z) == pytest.approx(m0, rel=0.10)


def test_sea_needs_a_vessel_model():
    sc = towenv.load_scene("two_part_tow_1").to_dict()
    sc["sea"] = {"hs": 1.0, "tp": 5.0}
    with pytest.raises(towenv.SceneError, match="sea"):
        towenv.load_scene(sc)
    sc["vessel"]["model"] = "coastal_survey"
    assert towenv.load_scene(sc).sea.hs == 1.0
    sc["sea"] = {"hs": 1.0}
    with pytest.raises(towenv.SceneError, match="hs"):
        towenv.load_scene(sc)


def test_orbital_velocity_kernel_matches_wave_record():
    """The numba orbital-velocity evaluation equals towenv.sea's numpy kinematics (deep water)."""
    from towenv.core.kernels import wave_orbital_velocity
    from towenv.sea import synthesize
    w = synthesize(SeaState(2.0, 7.0, spreading_s=4.0), duration=600.0, seed=5, n_components=120)
    rng = np.random.default_rng(0)
    out = np.empty(3)
    for _ in range(20):
        x, y, z, t = rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-30, 0), rng.uniform(0, 300)
        ref, _ = w.kinematics(t, x, y, z)
        wave_orbital_velocity(x, y, z, t, w.amplitude, w.omega, w.kx, w.ky, w.k, w.phase, out)
        np.testing.assert_allclose(out, ref, rtol=1e-9, atol=1e-12)


def test_orbital_velocities_act_near_the_surface_only():
    """With orbital velocities on, a shallow tow responds more than without; a deep one hardly changes."""
    def run(depth_factor, orbital):
        sc = towenv.load_scene("peer_deck").to_dict()
        sc["vessel"].update(model="coastal_survey", speed=1.0)
        sc["sea"] = {"hs": 2.0, "tp": 6.0, "heading_deg": 90.0, "orbital_velocities": orbital}
        sc["lines"][0]["length"] = 100.0 * depth_factor
        sim = towenv.Simulator(sc, dt=0.05)
        sim.advance(60.0)
        ys = []
        for _ in range(200):
            sim.advance(0.25)
            ys.append(sim.body_state("ball")["position"][1])
        return np.std(ys)
    shallow_on, shallow_off = run(0.05, True), run(0.05, False)
    deep_on, deep_off = run(1.0, True), run(1.0, False)
    assert shallow_on > 1.2 * shallow_off
    assert deep_on == pytest.approx(deep_off, rel=0.05, abs=1e-3)


def test_scene_with_rao_table_reproduces_the_preset(tmp_path):
    """A user RAO table (here: the coastal preset tabulated at zero speed in head seas) drives the tow
    point like the preset does at zero speed (interpolation error only)."""
    from towenv.vessel import ClosedFormRAO, RAOTable
    table = RAOTable.from_rao(ClosedFormRAO("coastal_survey"), np.linspace(0.2, 6.0, 300), headings_deg=(180.0,))
    csv = table.to_csv(tmp_path / "raos.csv")
    base = towenv.load_scene("two_part_coastal_ss4").to_dict()
    base["vessel"]["speed"] = 0.0
    base["compensator"] = None
    a = towenv.Simulator(towenv.load_scene({k: v for k, v in base.items() if v is not None}), dt=0.1)
    base["vessel"].update(model=None, rao_file=str(csv), lever_arm=[-7.5, 0.0, 2.0])
    b = towenv.Simulator(towenv.load_scene({k: v for k, v in base.items() if v is not None}), dt=0.1)
    t = np.linspace(50.0, 250.0, 2001)
    za = a.path.position(t)[:, 2]
    zb = b.path.position(t)[:, 2]
    assert np.std(za) > 0.05
    assert np.max(np.abs(za - zb)) < 0.02 * np.ptp(za)


def test_scene_with_measured_motion_record(tmp_path):
    """A measured vessel motion record (pure heave here) is replayed at the tow point."""
    t = np.arange(0.0, 200.0, 0.1)
    heave = 0.3 * np.sin(2 * np.pi * t / 7.0)
    csv = tmp_path / "motion.csv"
    csv.write_text("t,surge,sway,heave,roll,pitch,yaw\n" + "\n".join(f"{a},0,0,{b},0,0,0" for a, b in zip(t, heave)))
    sc = towenv.load_scene("peer_deck").to_dict()
    sc["vessel"].update(motion_file=str(csv), lever_arm=[0.0, 0.0, 0.0], ramp={"type": "none", "duration": 0.0})
    sim = towenv.Simulator(sc, dt=0.1)
    z = sim.path.position(np.array([10.0, 20.0]))[:, 2]
    expected = 0.3 * np.sin(2 * np.pi * np.array([10.0, 20.0]) / 7.0)
    np.testing.assert_allclose(z, expected - np.mean(heave), atol=1e-3)
