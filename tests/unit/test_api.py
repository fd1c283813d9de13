"""Public API: simulate/Result, Simulator stepping, excitation sources, helpers, bad input."""
import math

import numpy as np
import pytest

import towenv
from towenv.core.excitation import TowPointPath

from helpers import peer_deck


def test_simulate_result_save_load_roundtrip(tmp_path):
    res = towenv.simulate("two_part_tow_1", duration=10.0, record_interval=0.1)
    assert res.t[0] == 0.0 and res.t[-1] == pytest.approx(10.0)
    fish = res.bodies["fish"]
    assert fish["position"].shape == (len(res.t), 3) and fish["euler"].shape == (len(res.t), 3)
    assert res.lines["primary"]["tensions"].shape[0] == len(res.t)
    assert np.all(np.isfinite(res.top_tension)) and res.meta["real_time_factor"] > 0
    path = res.save(tmp_path / "run")
    back = towenv.Result.load(path)
    np.testing.assert_array_equal(back.t, res.t)
    np.testing.assert_array_equal(back.bodies["fish"]["euler"], fish["euler"])
    np.testing.assert_array_equal(back.lines["secondary"]["positions"], res.lines["secondary"]["positions"])
    assert back.meta["scene"] == "two_part_tow_1"


def test_simulate_accepts_overrides_and_checks_duration():
    res = towenv.simulate(peer_deck(), duration=2.0, dt=0.01)
    assert res.meta["dt"] == 0.01
    with pytest.raises(ValueError, match="duration"):
        towenv.simulate(peer_deck(), duration=-1.0)


def test_time_series_excitation_from_file(tmp_path):
    t = np.linspace(0.0, 20.0, 201)
    z = 0.5 * np.sin(2 * np.pi * t / 5.0)
    csv = tmp_path / "motion.csv"
    csv.write_text("t,x,y,z\n" + "\n".join(f"{a},0,0,{b}" for a, b in zip(t, z)))
    d = peer_deck()
    d["vessel"]["excitation"] = [dict(type="time_series", file=str(csv))]
    d["vessel"]["ramp"] = dict(type="none", duration=0.0)
    sim = towenv.Simulator(d)
    sim.advance(3.0)
    assert sim.positions[sim.system.top_node, 2] == pytest.approx(0.5 * np.sin(2 * np.pi * 3.0 / 5.0), abs=1e-9)


def test_speed_profile_4_to_12_and_turn_path_are_exact():
    vessel = dict(speed=4.0, manoeuvres=[dict(type="speed_change", start_time=10.0, duration=20.0, final_speed=12.0),
                                         dict(type="turn", start_time=40.0, radius=100.0, angle_deg=90.0, speed=12.0)])
    path = TowPointPath(vessel)
    x, psi, v = path.mean_path(np.array([10.0, 30.0, 40.0, 40.0 + 100 * math.pi / 2 / 12.0]))
    assert v.tolist() == pytest.approx([4.0, 12.0, 12.0, 12.0])
    assert x[1, 0] == pytest.approx(40.0 + 20.0 * 8.0, abs=1e-9)          # 4·10 + (4+12)/2·20
    assert x[3, 0] - x[2, 0] == pytest.approx(100.0, abs=1e-9)           # quarter circle to port
    assert x[3, 1] - x[2, 1] == pytest.approx(100.0, abs=1e-9)
    assert psi[3] == pytest.approx(math.pi / 2)
    # chunking does not matter: positions are analytic
    t = np.linspace(0, 60, 601)
    np.testing.assert_array_equal(path.position(t)[300:], path.position(t[300:]))


def test_speed_change_tow_runs():
    d = peer_deck(speed=4.0, dt=0.05)
    d["vessel"]["manoeuvres"] = [dict(type="speed_change", start_time=5.0, duration=20.0, final_speed=12.0)]
    res = towenv.simulate(d, duration=40.0)
    assert res.bodies["ball"]["position"][-1, 2] > res.bodies["ball"]["position"][0, 2]   # rises when faster


def test_time_step_helpers():
    assert towenv.time_step_guide(2.0) == pytest.approx(0.048)
    with pytest.raises(ValueError, match="scheme"):
        towenv.time_step_guide(2.0, scheme="rk4")
    from towenv.core.simulator import thesis_time_step, transverse_courant_time_step
    assert thesis_time_step(5.0, 2e7, 1.0) == pytest.approx(5.0 / (10 * math.sqrt(2e7)))
    assert transverse_courant_time_step(5.0, 4563.0, 1.0, 0.322) == pytest.approx(0.5 * 5 / math.sqrt(4563 / 1.322))


def test_bad_scene_gives_one_clear_error():
    d = peer_deck()
    d["lines"][0]["length"] = -5.0
    with pytest.raises(towenv.SceneError, match=r"lines\[0\]\.length"):
        towenv.Simulator(d)


def test_snapshot_restore_is_cheap_and_exact():
    sim = towenv.Simulator("ablow_turn_1km")
    snap = sim.snapshot()
    sim.advance(1.0)
    sim.restore(snap)
    np.testing.assert_array_equal(sim.positions, snap.hist_r[0])
