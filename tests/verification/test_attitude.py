"""Body attitude without the Euler-angle singularity: the moving attitude chart of the Houbolt kernel.

* runs whose bodies never re-chart are bit-identical to the stored trajectories of the pre-chart kernel
  (tests/data/houbolt_reference.npz, see tests/data/make_houbolt_reference.py) on the machine that made the
  file, and agree to round-off on others (numba compiles for the host CPU);
* ``kernels.rechart_body`` equals its numpy twin and leaves every stored attitude unchanged; one Houbolt
  step from a re-charted state equals the twin's step;
* torque-free rigid bodies tumble through pitch ±90° any number of times: exact conservation for a pure
  pitch spin, second-order convergence of the energy and angular-momentum errors with a wobble;
* ``body_state`` reports the physical attitude (Euler angles, rotation matrix, quaternion), and
  snapshot / restore / reset carry the chart;
* the Hover et al. SS6 locked-compensator run (validation case 3b, cg-mapped towfish), which used to stop
  at t = 46 s with the ±85° limit, runs its 700 s.
"""
from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

import towenv
from towenv.core import kernels as K
from towenv.verification import twin
from towenv.core.simulator import physical_attitude, quaternion_from_rotation

from helpers import DATA


# ----------------------------------------------------------------------------------------------
# bit-identity with the pre-chart kernel
# ----------------------------------------------------------------------------------------------
def _reference_cases():
    import importlib.util
    spec = importlib.util.spec_from_file_location("make_houbolt_reference", DATA / "make_houbolt_reference.py")
    ref = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ref)
    return ref


@pytest.mark.parametrize("scene", ["two_part_tow_1", "series_multitow", "hover_deep_tow", "hover_ss6_locked_cg"])
def test_no_rechart_runs_are_bit_identical_to_the_euler_angle_kernel(scene):
    ref = _reference_cases()
    stored = np.load(DATA / "houbolt_reference.npz")
    overrides, steps = ref.CASES[scene]
    # the reference predates the monolithic series coupling (the default since 2026-12): the series tow is run
    # with the coupling it was made with, which the current code keeps as solver.series_coupling = "relaxed"
    # (tests/unit/test_series_coupling.py checks that both converge to the same solution)
    if scene == "series_multitow":
        overrides = dict(overrides, **{"solver.series_coupling": "relaxed"})
    # likewise the Newton predictor the file was made with: the quadratic one (solver.predictor, 2026-12-06; the
    # adaptive default converges to the same solution within the Newton tolerance: tests/unit/test_predictor.py)
    overrides = dict(overrides, **{"solver.predictor": "quadratic"})
    # and the bodies' derivatives computed every step, as then (solver.body_derivative_refresh = 1; the default 10
    # reuses them and converges to the same solution within the tolerance: tests/unit/test_body_derivatives.py)
    overrides = dict(overrides, **{"solver.body_derivative_refresh": 1})
    # and the free nodes' Newton matrices built at every iteration (solver.cable_jacobian_refresh = 1; the default 10
    # reuses them, a modified Newton, converging within the tolerance: tests/unit/test_cable_jacobian.py)
    overrides = dict(overrides, **{"solver.cable_jacobian_refresh": 1})
    sim = ref.run(scene, overrides, steps)
    assert sim.stats["recharts"] == 0
    assert np.all(sim.body_chart == np.eye(3))
    made_here = "fingerprint" in stored and str(stored["fingerprint"]) == ref.fingerprint()
    for key in ("hist_r", "hist_ang", "tens_hist", "top_react"):
        got, want = getattr(sim, key), stored[f"{scene}::{key}"]
        if made_here:
            assert np.array_equal(got, want), key
        else:
            # another CPU or library build: numba's code generation differs in the last bits (observed
            # ≤ 2e-14 relative in positions, 1e-11 in tensions after 300 steps), far inside the Newton
            # tolerance; bit-identity is checked on the machine that made the file
            assert np.allclose(got, want, rtol=0.0, atol=1e-9 * max(np.max(np.abs(want)), 1.0)), key
    assert np.array_equal(sim.counters[:4], stored[f"{scene}::counters"])


# ----------------------------------------------------------------------------------------------
# the re-chart map
# ----------------------------------------------------------------------------------------------
def _random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def test_rechart_matches_twin_and_preserves_every_attitude():
    rng = np.random.default_rng(7)
    nb = 3
    for trial in range(20):
        chart = np.stack([_random_rotation(rng) if trial % 2 else np.eye(3) for _ in range(nb)])
        a0 = rng.uniform([-3, -1.4, -3], [3, 1.4, 3], size=(nb, 3))
        rate = rng.normal(scale=0.05, size=(nb, 3))          # one step's worth of rotation
        hist = np.stack([a0, a0 - rate, a0 - 2 * rate + rng.normal(scale=0.002, size=(nb, 3))])
        b = trial % nb
        h_k, c_k = hist.copy(), chart.copy()
        K.rechart_body(b, h_k, c_k, np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty(3))
        h_t, c_t = twin.rechart_np(hist, chart, b)
        np.testing.assert_allclose(c_k, c_t, atol=1e-13)
        np.testing.assert_allclose(h_k, h_t, atol=1e-12)
        assert np.all(h_k[0, b] == 0.0)
        # other bodies untouched; the re-charted body's three attitudes unchanged
        others = [i for i in range(nb) if i != b]
        assert np.array_equal(h_k[:, others], hist[:, others]) and np.array_equal(c_k[others], chart[others])
        for lv in range(3):
            old = twin.body_rotation_np(hist[lv, b], chart[b])
            new = np.empty((3, 3))
            K.body_rotation(h_k[lv, b], c_k[b], new)
            np.testing.assert_allclose(new, old, atol=1e-14)
        np.testing.assert_allclose(c_k[b] @ c_k[b].T, np.eye(3), atol=1e-15)
        # in the new chart the older levels' Euler angles are small: about the rotation angle between them
        # and the current attitude (Euler angles ≈ rotation-vector components near zero)
        for lv in (1, 2):
            loc = twin.rotation_matrix_np(*h_k[lv, b])
            angle = math.acos(min(1.0, (np.trace(loc) - 1) / 2))
            assert np.max(np.abs(h_k[lv, b])) < 1.5 * angle + 1e-12


def test_body_rotation_with_identity_chart_is_the_plain_rotation_matrix():
    rng = np.random.default_rng(3)
    for _ in range(50):
        ang = rng.uniform(-3, 3, size=3)
        a = np.empty((3, 3))
        b = np.empty((3, 3))
        K.rotation_matrix(ang[0], ang[1], ang[2], a)
        K.body_rotation(ang, np.eye(3), b)
        assert np.array_equal(a, b)


def test_euler_from_rotation_round_trip_and_gimbal_lock():
    rng = np.random.default_rng(11)
    out = np.empty(3)
    lam = np.empty((3, 3))
    for _ in range(200):
        ang = rng.uniform([-math.pi, -1.5, -math.pi], [math.pi, 1.5, math.pi])
        K.rotation_matrix(ang[0], ang[1], ang[2], lam)
        K.euler_from_rotation(lam, out)
        np.testing.assert_allclose(out, ang, atol=1e-12)
        np.testing.assert_allclose(out, twin.attitude_euler_np(lam), atol=1e-12)
    # pitch exactly ±90°: roll set to 0, the attitude still reproduced
    for pitch in (math.pi / 2, -math.pi / 2):
        K.rotation_matrix(0.4, pitch, 1.1, lam)
        K.euler_from_rotation(lam, out)
        back = np.empty((3, 3))
        K.rotation_matrix(out[0], out[1], out[2], back)
        assert out[0] == 0.0 and abs(out[1] - pitch) < 1e-7
        np.testing.assert_allclose(back, lam, atol=1e-12)


def test_houbolt_step_from_a_recharted_state_matches_twin():
    """Series tow (aft tow points carried by their bodies): re-chart every body to a random chart, then one
    kernel step equals the twin's step (1e-9, as in tests/verification/test_twin.py), and equals the step taken without
    re-charting to within the scheme's local error (the two charts are two coordinate systems of the same
    attitude)."""
    from twin_cases import EXCITATION, SCENES, _simulator, kernel_and_twin_step

    sim = _simulator(SCENES["series"](excitation=EXCITATION))
    sim.advance(2.0)
    plain = sim.snapshot()
    nb = sim.system.n_rigid
    for b in range(nb):
        K.rechart_body(b, sim.hist_ang, sim.body_chart, np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)),
                       np.empty(3))
    assert not np.allclose(sim.body_chart, np.eye(3))
    # as kernels.advance does after a re-chart: the predictor's memory holds angles of the old charts (and for
    # the comparison below both steps start from the same, lower-order predictor)
    sim.forget_step_memory()
    top = sim.path.position(np.array([sim.t + sim.dt]))[0]
    res = kernel_and_twin_step(sim)
    np.testing.assert_array_equal(res.body_chart, sim.body_chart)
    charted_r = sim.hist_r[0].copy()
    charted_att = [twin.body_rotation_np(sim.hist_ang[0, b], sim.body_chart[b]) for b in range(nb)]
    sim.restore(plain)
    sim.forget_step_memory()
    st, *_ = K.houbolt_step_entry(sim.dt, top, *sim._args, sim.settings.array(), sim._state, sim._ws, sim.comp)
    assert st == K.OK
    # local error of one step: positions within 1e-6 m, attitudes within 1e-6 rad
    assert np.max(np.abs(sim.hist_r[0] - charted_r)) < 1e-6
    for b in range(nb):
        assert np.max(np.abs(twin.body_rotation_np(sim.hist_ang[0, b], sim.body_chart[b]) - charted_att[b])) < 1e-6


# ----------------------------------------------------------------------------------------------
# torque-free tumbling through pitch ±90°
# ----------------------------------------------------------------------------------------------
def spin_scene(dt, inertia=(4.0, 9.0, 6.0), added_inertia=(0.0, 0.0, 0.0)):
    """A 100 kg rigid body with its centre of mass and buoyancy at the tow point, no hydrodynamic loads, no
    added mass or inertia, on a 10 m tether from a fixed tow point: its rotation is decoupled from the
    tether and torque-free (Euler's equations about the centre of mass)."""
    table = {"incidence_deg": [0.0, 90.0], "drag": [0.0, 0.0], "lift": [0.0, 0.0], "moment": [0.0, 0.0]}
    return {"name": "free_spin", "water": {"density": 1025.0, "gravity": 9.80665}, "vessel": {"speed": 0.0},
            "lines": [{"name": "tether", "length": 10.0, "segments": 2, "top": "vessel", "bottom": {"body": "fish"},
                       "diameter": 0.02, "mass_per_length": 1.0, "EA": 1e7, "cn": 0.0, "ct": 0.0, "can": 0.0,
                       "cat": 0.0}],
            "bodies": [{"name": "fish", "kind": "fish", "mass": 100.0, "volume": 0.02, "cg": [0.0, 0.0, 0.0],
                        "cb": [0.0, 0.0, 0.0], "inertia": list(inertia), "reference_area": 0.1,
                        "reference_length": 1.0, "coefficients": table, "rotational_damping": [0.0, 0.0, 0.0],
                        "added_inertia": list(added_inertia),
                        "quadratic_rotational_damping": [0.0, 0.0, 0.0]}],
            "solver": {"dt": dt, "angle_tolerance": 1e-10, "tolerance": 1e-3}}


def _tumble(dt, omega0, duration=20.0, every=0.1, **scene_kw):
    """Start at zero attitude with body rates ``omega0`` (history on the constant-rate line); return the
    simulator and the time series (t, energy ½ωᵀIω, angular momentum R I ω in global axes, pitch), I the
    whole rotational inertia (rigid + added)."""
    sim = towenv.Simulator(spin_scene(dt, **scene_kw))
    inertia = np.diag(sim.system.bp[0, 10:13] + sim.system.bp[0, 23:26])
    for k in range(3):
        sim.hist_ang[k, 0] = -k * dt * np.asarray(omega0)      # Euler rates = body rates at zero angles
    rows = []
    for _ in range(int(round(duration / every))):
        sim.advance(every)
        st = sim.body_state("fish")
        w = st["omega"]
        rows.append((sim.t, 0.5 * w @ inertia @ w, *(st["rotation"] @ inertia @ w), st["euler"][1]))
    return sim, np.array(rows)


def test_pure_pitch_spin_passes_the_vertical_exactly():
    """Spin about the body y axis at 3 rad/s for 20 s (~10 turns, dozens of re-charts): the Euler angles of
    each chart are linear in time, which Houbolt integrates exactly, so energy and angular momentum are
    conserved to round-off through every re-chart."""
    sim, rows = _tumble(0.02, (0.0, 3.0, 0.0))
    assert sim.stats["recharts"] >= 50
    assert sim.stats["step_cuts"] == 0
    assert np.max(np.abs(rows[:, 5])) > math.radians(89.0)       # pitch went through ±90°
    energy = rows[:, 1]
    mom = rows[:, 2:5]
    assert np.max(np.abs(energy / energy[0] - 1)) < 1e-10
    assert np.max(np.linalg.norm(mom - mom[0], axis=1)) / np.linalg.norm(mom[0]) < 1e-10


def test_tumbling_body_conserves_energy_and_momentum_to_second_order():
    """General tumbling (rates (0.3, 3, 0.2) rad/s, principal inertias 4, 9, 6 kg m²), 20 s. Houbolt is second
    order, so the relative energy error and the drift of the global angular momentum vector must stay below
    the global error bound of a second-order scheme, (ωΔt)² · ωT / 12 (ω = |ω₀|, T the run length), and
    shrink at least 2^1.8-fold when Δt is halved. Measured (default re-chart pitch 30°): energy 1.9e-3 and
    4.2e-4, momentum 2.7e-3 and 6.7e-4 at Δt = 0.01 and 0.005 s, against bounds 4.6e-3 and 1.1e-3."""
    omega0 = np.array([0.3, 3.0, 0.2])
    wn = float(np.linalg.norm(omega0))
    errs = []
    for dt in (0.01, 0.005):
        sim, rows = _tumble(dt, omega0)
        assert sim.stats["recharts"] > 20
        assert np.max(np.abs(rows[:, 5])) > math.radians(85.0)
        energy = rows[:, 1]
        mom = rows[:, 2:5]
        e_err = np.max(np.abs(energy / energy[0] - 1))
        l_err = np.max(np.linalg.norm(mom - mom[0], axis=1)) / np.linalg.norm(mom[0])
        bound = (wn * dt) ** 2 * wn * 20.0 / 12.0
        assert e_err < bound, (dt, e_err, bound)
        assert l_err < bound, (dt, l_err, bound)
        errs.append((e_err, l_err))
    assert errs[0][0] / errs[1][0] > 2 ** 1.8
    assert errs[0][1] / errs[1][1] > 2 ** 1.8


def test_added_inertia_tumbles_like_the_same_rigid_inertia():
    """Kirchhoff: a body whose rotational inertia is part rigid, part added (diagonal, no drag, no added mass)
    rotates exactly like a rigid body with the summed inertia — the added inertia belongs in the gyroscopic
    term ω × (Aω) as well as in Aω̇. Split (4, 9, 6) kg m² into rigid (2, 4, 5.5) + added (2, 5, 0.5): the
    trajectory equals the all-rigid one to round-off and keeps the energy bound of the rigid test. (With
    the added inertia left out of the gyroscopic term, as before, this test fails.)"""
    omega0 = np.array([0.3, 3.0, 0.2])
    _, rigid = _tumble(0.01, omega0, duration=10.0)
    _, split = _tumble(0.01, omega0, duration=10.0, inertia=(2.0, 4.0, 5.5), added_inertia=(2.0, 5.0, 0.5))
    assert np.allclose(split, rigid, rtol=1e-9, atol=1e-9)
    wn = float(np.linalg.norm(omega0))
    energy = split[:, 1]
    assert np.max(np.abs(energy / energy[0] - 1)) < (wn * 0.01) ** 2 * wn * 10.0 / 12.0


def test_rechart_every_step_is_the_accurate_option():
    """``settings.rechart_pitch = 0`` re-charts before every step (local angles always one step small): the
    attitude error of the tumbling body is several times smaller than with the default threshold."""
    omega0 = np.array([0.3, 3.0, 0.2])
    _, rows_default = _tumble(0.01, omega0, duration=10.0)
    sim = towenv.Simulator(spin_scene(0.01))
    sim.settings.rechart_pitch = 0.0
    inertia = np.diag(sim.system.bp[0, 10:13])
    for k in range(3):
        sim.hist_ang[k, 0] = -k * 0.01 * omega0
    mom = []
    for _ in range(100):
        sim.advance(0.1)
        st = sim.body_state("fish")
        mom.append(st["rotation"] @ inertia @ st["omega"])
    mom = np.array(mom)
    assert sim.stats["recharts"] >= sim.stats["steps"] - 1       # all but the first (pitch exactly 0)
    err_every = np.max(np.linalg.norm(mom - mom[0], axis=1))
    err_default = np.max(np.linalg.norm(rows_default[:, 2:5] - rows_default[0, 2:5], axis=1))
    assert err_every < 0.5 * err_default
    with pytest.raises(ValueError, match="rechart_pitch"):
        sim.settings.rechart_pitch = 1.4
        sim.advance(0.1)


# ----------------------------------------------------------------------------------------------
# outputs, snapshots
# ----------------------------------------------------------------------------------------------
def test_body_state_reports_the_physical_attitude_past_the_vertical():
    sim, _ = _tumble(0.02, (0.0, 3.0, 0.0), duration=0.6)      # pitch ≈ 1.8 rad: nose past straight down
    st = sim.body_state("fish")
    R = st["rotation"]
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    # the same attitude from the reported Euler angles (pitch folded into [−90°, 90°], roll/yaw flipped)
    lam = np.empty((3, 3))
    K.rotation_matrix(*st["euler"], lam)
    np.testing.assert_allclose(lam.T, R, atol=1e-12)
    assert abs(st["euler"][1]) <= math.pi / 2
    assert abs(abs(st["euler"][0]) - math.pi) < 1e-6 and abs(abs(st["euler"][2]) - math.pi) < 1e-6
    # the body x axis (nose) after 1.8 rad of nose-down pitch about y
    theta = 3.0 * sim.t
    np.testing.assert_allclose(R[:, 0], [math.cos(theta), 0.0, -math.sin(theta)], atol=1e-9)
    # quaternion of R, w ≥ 0, and its rotation is R
    q = st["quaternion"]
    w, x, y, z = q
    Rq = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                   [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                   [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    assert w >= 0.0
    np.testing.assert_allclose(Rq, R, atol=1e-12)
    np.testing.assert_allclose(st["omega"], [0.0, 3.0, 0.0], atol=1e-9)
    # the vectorised helper for recorded (chart, local angle) pairs agrees
    eul, Rv = physical_attitude(sim.body_chart[0], sim.hist_ang[0, 0])
    np.testing.assert_allclose(eul, st["euler"], atol=1e-12)
    np.testing.assert_allclose(Rv, R, atol=1e-12)


def test_quaternion_near_half_turn():
    for ang in ([math.pi, 0.0, 0.0], [0.0, 0.0, math.pi - 1e-9], [0.3, -1.2, 2.9]):
        lam = np.empty((3, 3))
        K.rotation_matrix(*ang, lam)
        q = quaternion_from_rotation(lam.T)
        assert abs(np.linalg.norm(q) - 1) < 1e-14 and q[0] >= 0


def test_snapshot_restore_and_reset_carry_the_chart():
    sim, _ = _tumble(0.02, (0.3, 3.0, 0.2), duration=1.0)
    assert sim.stats["recharts"] > 0
    snap = sim.snapshot()
    sim.advance(1.0)
    after = (sim.hist_r.copy(), sim.hist_ang.copy(), sim.body_chart.copy())
    sim.restore(snap)
    np.testing.assert_array_equal(sim.body_chart, snap.chart)
    sim.advance(1.0)
    for a, b in zip(after, (sim.hist_r, sim.hist_ang, sim.body_chart)):
        assert np.array_equal(a, b)
    sim.reset()
    assert np.all(sim.body_chart == np.eye(3))


# ----------------------------------------------------------------------------------------------
# the validation case that used to stop
# ----------------------------------------------------------------------------------------------
def test_hover_ss6_locked_cg_mapped_runs_700_s():
    """Validation case 3b, SS6, locked compensator, cg-mapped towfish, seed 1 (the run the Euler-angle
    kernel stopped at t = 46.4 s with 'body pitch reached ±85°'): 700 s now complete; the slack-snapping
    towfish passes pitch ±60° many times (re-charts) and reaches the vertical."""
    from towenv.validation import hover as H

    rao = H._rao_csv(tempfile.mkdtemp(), H.deck_gain())
    sim = towenv.Simulator(H.cg_mapped(H._comp_scene(rao, 6, "locked", 0.0, 0.0, 40.0, seed=1)))
    pmax = 0.0
    for _ in range(700):
        sim.advance(1.0)
        pmax = max(pmax, abs(sim.body_state("towfish")["euler"][1]))
    assert sim.t == pytest.approx(700.0)
    assert sim.stats["recharts"] > 10
    assert pmax > math.radians(85.0)
    assert np.all(np.isfinite(sim.hist_r))


def test_recorded_result_reports_the_physical_attitude():
    from towenv.core.run import Recorder

    sim = towenv.Simulator(spin_scene(0.02))
    for k in range(3):
        sim.hist_ang[k, 0] = -k * 0.02 * np.array([0.3, 3.0, 0.2])
    rec = Recorder(sim, 41)
    rec.record()
    states = []
    for _ in range(40):
        sim.advance_steps(5)
        rec.record()
        states.append(sim.body_state("fish"))
    assert sim.stats["recharts"] > 5
    res = rec.result()
    np.testing.assert_allclose(res.bodies["fish"]["euler"][1:], [s["euler"] for s in states], atol=1e-12)
    np.testing.assert_allclose(res.bodies["fish"]["omega"][1:], [s["omega"] for s in states], atol=1e-12)


@pytest.mark.parametrize("method, dt", [("rk4", 1e-3), ("generalized_alpha", 0.01), ("newmark", 0.01)])
def test_schemes_without_the_chart_refuse_the_vertical_clearly(method, dt):
    """Issue 18, item 2 ("the moving attitude chart in every scheme, or a clear refusal"): the explicit and
    α schemes integrate plain Euler angles; a body spun through the vertical stops the run at ±85° with an
    error naming the limit and the Houbolt scheme — not as an 'unstable' step — and the state is the last
    good step. Houbolt passes the same spin (test_pure_pitch_spin_passes_the_vertical_exactly)."""
    sim = towenv.Simulator(dict(spin_scene(dt), solver={"dt": dt, "method": method}))
    if method == "rk4":
        sim.scheme.xomg[0] = (0.0, 3.0, 0.0)          # body pitch rate 3 rad/s: 85° after ~0.5 s
    else:
        sim.scheme.xdang[0] = (0.0, 3.0, 0.0)
    with pytest.raises(towenv.SimulationDivergence) as err:
        sim.advance(1.0)
    msg = str(err.value)
    assert "pitch reached ±85°" in msg and 'solver.method = "houbolt"' in msg and "unstable" not in msg
    assert 0.45 < err.value.time < 0.55
    assert abs(sim.body_state("fish")["euler"][1]) < math.radians(85.0)
