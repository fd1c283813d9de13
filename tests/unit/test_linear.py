"""Linearised frequency-domain model (towenv.linear): closed forms, the time-domain simulator, convergence
of the equivalent linearisation, and input checking. Tolerances are justified next to each assertion."""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from towenv.core.run import simulate
from towenv.core.simulator import load
from towenv.linear import LinearisationError, LinearModel
from towenv.linear import eqlin
from towenv.sea import SeaState
from towenv.validation import hover as H

RHO, G = 1025.0, 9.81


def _light_cable(length=100.0, segments=10, EA=1e9, **kw):
    # neutrally buoyant thin cable (bulk density 1019 kg/m^3) without drag or added mass
    d = {"name": "cable", "length": length, "segments": segments, "top": "vessel", "bottom": {"body": "weight"},
         "diameter": 0.005, "mass_per_length": 0.02, "EA": EA, "cn": 0.0, "ct": 0.0, "can": 0.0, "cat": 0.0}
    d.update(kw)
    return d


def _clump_scene(mass=1000.0, volume=0.0, ca=0.0, cda=0.0, **cable):
    return {"name": "lin_clump", "water": {"density": RHO, "gravity": G}, "vessel": {"speed": 0.0},
            "lines": [_light_cable(**cable)],
            "bodies": [{"name": "weight", "kind": "clump", "mass": mass, "volume": volume,
                        "added_mass_coefficient": ca, "drag_area": cda}],
            "solver": {"dt": 0.01}}


@pytest.fixture(scope="module")
def hover_planar():
    return LinearModel(H.planar_scene())


# -------------------------------------------------------------------------------------------------
# closed forms
# -------------------------------------------------------------------------------------------------
def test_pendulum_and_axial_natural_frequencies():
    """A heavy clump on a light 100 m cable: pendulum and axial spring–mass, with the cable's mass (2 kg,
    0.2 % of the clump's) counted as μL/3 as for a continuous string (the 10-node lumping differs from
    that by 3e-6): ω_p = √(T/(ℓ m_e)), ω_a = √(EA/(L m_e)), m_e = m + μL/3, to 1e-4."""
    m, L, EA, mu = 1000.0, 100.0, 1e9, 0.02
    lm = LinearModel(_clump_scene(mass=m))
    w = lm.natural_frequencies()
    T = lm.T0.max()
    ell = L * (1 + T / EA)
    me = m + mu * L / 3
    pend = math.sqrt(T / (ell * me))
    axial = math.sqrt(EA / L / me)
    assert w[0] == pytest.approx(pend, rel=1e-4)
    assert w[1] == pytest.approx(pend, rel=1e-4)    # the two horizontal directions
    assert np.min(np.abs(w / axial - 1)) < 1e-4
    assert abs(pend - math.sqrt(G / L)) / pend < 1e-3


def test_natural_frequencies_match_modal_analysis():
    """Same mass and stiffness as towenv.core.modal (independent assembly, analytic tangent stiffness):
    the finite-difference Jacobians agree to 1e-6 relative (central differences, h = 1e-5 m)."""
    from towenv.core.modal import natural_frequencies
    from towenv.core.simulator import Simulator
    sc = _clump_scene(mass=300.0, volume=0.05, ca=0.5, segments=6, EA=5e6, can=1.0, cn=1.2, mass_per_length=0.08,
                      diameter=0.01)
    lm = LinearModel(sc)
    w_lin = lm.natural_frequencies()
    sim = Simulator(sc, settle_time=0.0)
    w_modal, _ = natural_frequencies(sim)
    np.testing.assert_allclose(w_lin[:8], w_modal[:8], rtol=1e-6)


def test_compensator_is_a_spring_mass_damper():
    """A rigid (EA/L = 1e8 N/m) 10 m cable and a 500 kg clump on a compensator (k, b, m_c), no drag: the load
    moves as one mass on the spring and damper, y/u = (k + iωb)/(k − ω²(m_c + M) + iωb). The cable's axial
    mode is at 447 rad/s, so below 10 rad/s the flexibility changes the ratio by < (10/447)² = 5e-4."""
    k, b, mc, m = 2.0e4, 3.0e3, 200.0, 500.0
    sc = _clump_scene(mass=m, volume=0.05, length=10.0, segments=2)
    sc["compensator"] = {"mode": "passive", "stiffness": k, "damping": b, "mass": mc, "stroke": 4.0,
                         "stiffness_bounds": [0.0, 1e6], "damping_bounds": [0.0, 1e6]}
    lm = LinearModel(sc)
    om = np.array([0.5, 2.0, 5.0, 6.3, 10.0])
    r = lm.response(om)
    M = mc + m + 0.02 * 10.0
    y = (k + 1j * om * b) / (k - om ** 2 * M + 1j * om * b)
    np.testing.assert_allclose(r.rao["fish_heave"], y, rtol=2e-3)
    assert np.all(np.abs(r.rao["stroke"] - (y - 1.0)) <= 2e-3 * np.abs(y))
    locked = lm.response(om, compensator="locked")
    np.testing.assert_allclose(locked.rao["fish_heave"], 1.0, rtol=2e-3)
    np.testing.assert_array_equal(locked.rao["stroke"], 0.0)


def test_low_frequency_limit_vertical_cable(hover_planar):
    """ω → 0: the hanging cable and fish translate with the top (heave RAO → 1) and the dynamic tensions
    vanish (inertia ω²·5000 kg and drag are both O(1e-3) N per m at ω = 1e-3)."""
    r = hover_planar.response(np.array([1e-3, 3e-3]))
    np.testing.assert_allclose(np.abs(r.rao["fish_heave"]), 1.0, atol=1e-4)
    assert np.all(np.abs(r.rao["top_tension"]) < 0.05)
    assert np.all(np.abs(r.rao["fish_tension"]) < 0.05)


def test_low_frequency_limit_towed_two_part():
    """Towed at 3 m/s in uniform flow the steady shape is translation invariant: at ω = 2e-4 rad/s
    (period 8.7 h, far beyond the ~30 s relaxation time L/U) the fish follows the top heave to 1 %."""
    lm = LinearModel("two_part_tow_1")
    r = lm.response(np.array([2e-4]))
    assert abs(r.rao["fish_heave"][0] - 1.0) < 0.01
    assert abs(r.rao["depressor_heave"][0] - 1.0) < 0.01


def test_deep_tow_heave_matches_hover_axial_string(hover_planar):
    """Hover's appendix model (axial string + end mass, drag linearised by equal dissipation, as in
    validation case 3) holds where its assumptions do: vertical cable, no current, heave excitation.
    Remaining differences: 20 lumped segments, the towfish pitch coupling and the cable's tangential drag
    linearised at each node's amplitude instead of the top's (Hover's upper bound): 3 % on the heave, and on
    the top tension (the fish-end segment tension differs more: a segment's tension sits 100 m above the
    fish, so it is not compared)."""
    om = np.array([0.1, 0.3, 0.5, 0.7, 0.85, 1.0, 1.2, 1.5, 2.0])
    r = hover_planar.response(om)
    for i, w in enumerate(om):
        c = H._closed_form(w)
        assert abs(r.rao["fish_heave"][i]) == pytest.approx(abs(complex(c.p1)), rel=0.03), w
        assert abs(r.rao["top_tension"][i]) == pytest.approx(abs(complex(c.Tn)), rel=0.03), w


# -------------------------------------------------------------------------------------------------
# the nonlinear time-domain simulator
# -------------------------------------------------------------------------------------------------
def _td_amplitudes(d, om, amp, fish, line):
    from towenv.validation.common import harmonic, run_scene
    dd = H._sinusoid(d, om, amp=amp)
    per = 2 * math.pi / om
    out = run_scene(dd, 10 * per, record_interval=per / 50)
    assert out.ok, out.error
    w = out.result.window(out.result.t[-1] - 3 * per + 1e-9)
    A = harmonic(w.t, w.tow_point[:, 2] - w.tow_point[:, 2].mean(), om)
    b = w.bodies[fish]
    return {"fish_heave": harmonic(w.t, b["position"][:, 2], om) / A,
            "fish_pitch": harmonic(w.t, b["euler"][:, 1], om) / A,
            "fish_tension": harmonic(w.t, w.lines[line]["tensions"][:, -1], om) / A,
            "top_tension": harmonic(w.t, w.top_tension, om) / A}


@pytest.mark.parametrize("om", [0.8, 1.5])
def test_small_sinusoid_matches_time_domain_two_part_tow(om):
    """two_part_tow_1 at 3 m/s, 0.2 m top heave: the cables stay taut and the drag is dominated by the
    mean flow, so the linear model holds. 5 %: the time-domain record still carries the Houbolt numerical
    damping (~(ωΔt)²) and the drag's higher harmonics; measured differences are ≤ 2 %."""
    d = H.load_scene("two_part_tow_1").to_dict()
    lm = LinearModel(d)
    r = lm.response(np.array([om]), top=(0, 0, 0.2))
    td = _td_amplitudes(d, om, 0.2, "fish", "secondary")
    for k in ("fish_heave", "fish_pitch", "fish_tension", "top_tension"):
        assert abs(r.rao[k][0]) == pytest.approx(abs(td[k]), rel=0.05), k


def test_one_metre_sinusoid_matches_time_domain_deep_tow(hover_planar):
    """Hover's deep tow, 1 m top heave at 0.5 rad/s (taut, below the axial resonance): heave and tensions
    from the harmonic linearisation agree with the simulator to 5 % (measured ≤ 2 %)."""
    lm = hover_planar
    r = lm.response(np.array([0.5]))
    td = _td_amplitudes(H.planar_scene(), 0.5, 1.0, "towfish", "cable")
    for k in ("fish_heave", "fish_tension", "top_tension"):
        assert abs(r.rao[k][0]) == pytest.approx(abs(td[k]), rel=0.05), k


# -------------------------------------------------------------------------------------------------
# equivalent linearisation
# -------------------------------------------------------------------------------------------------
def _gh(n=10):
    gx, gw = np.polynomial.hermite_e.hermegauss(n)
    return gx, gw / gw.sum()


def test_harmonic_and_stochastic_drag_coefficients():
    """Scalar |v|v about zero mean: harmonic 8A/(3π) (16 phases: 1e-3, the aliasing of harmonic 15 of
    |cos|cos) and Gaussian √(8/π)σ (10 Gauss–Hermite points on a kinked integrand: 1 %). About a large
    mean flow U a small fluctuation (σ/U = 0.03) changes the tangent damping 2U (in line) and U (cross
    flow) only at second order, O(σ²/U²) = 1e-3 (the cross-flow term carries E[v_y²]/U, 2e-3)."""
    gx, gw = _gh()
    A, sig, U = 0.7, 0.4, 3.0
    out = np.zeros((1, 1, 3, 3))
    eqlin.point_equivalent(0, np.zeros((1, 3)), np.ones(1), np.array([[[A + 0j, 0, 0]]]), np.zeros((1, 3, 3)), 16,
                           gx, gw, out)
    assert out[0, 0, 0, 0] == pytest.approx(8 * A / (3 * math.pi), rel=1e-3)
    # a cross-flow perturbation meets the cycle-average |v| = 2A/π (16-phase average, 1.5 %)
    assert out[0, 0, 1, 1] == pytest.approx(2 * A / math.pi, rel=0.015)
    eqlin.point_equivalent(1, np.zeros((1, 3)), np.ones(1), np.zeros((1, 1, 3), complex),
                           np.diag([sig ** 2, 0, 0])[None], 16, gx, gw, out)
    assert out[0, 0, 0, 0] == pytest.approx(math.sqrt(8 / math.pi) * sig, rel=0.01)
    eqlin.point_equivalent(1, np.array([[U, 0, 0]]), np.ones(1), np.zeros((1, 1, 3), complex),
                           np.diag([0.01, 0.01, 0.01])[None], 16, gx, gw, out)
    assert out[0, 0, 0, 0] == pytest.approx(2 * U, rel=3e-3)
    assert out[0, 0, 1, 1] == pytest.approx(U, rel=3e-3)
    # cable along z, circular velocity path in the x–z plane: the normal (x) and tangential (z) drag
    # components each see a harmonic of amplitude A, the tangential one scaled by kt/kn = 0.1
    eqlin.cable_equivalent(0, np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), np.ones(1), np.array([0.1]),
                           np.array([[[A + 0j, 0, 1j * A]]]), np.zeros((1, 3, 3)), 16, gx, gw, out)
    assert out[0, 0, 0, 0] == pytest.approx(8 * A / (3 * math.pi), rel=1e-3)
    assert out[0, 0, 2, 2] == pytest.approx(0.1 * 8 * A / (3 * math.pi), rel=1e-3)
    assert abs(out[0, 0, 0, 2]) < 1e-12 and abs(out[0, 0, 2, 0]) < 1e-12


def test_equivalent_linearisation_converges(hover_planar):
    """Both iterations stop on their fixed-point residual within a bounded number of iterations, and a
    tighter tolerance moves the answers by less than the looser tolerance's order (0.3 %)."""
    om = np.linspace(0.05, 2.0, 50)
    r = hover_planar.response(om)
    assert r.converged and r.residual < hover_planar.tol and r.iterations <= 60
    ss = SeaState.from_code(5, "open_ocean", spectrum="bretschneider")
    s = hover_planar.spectral(ss)
    assert s.converged and s.iterations <= 60
    tight = LinearModel(H.planar_scene(), tol=1e-5)
    r2 = tight.response(om)
    s2 = tight.spectral(ss)
    assert r2.converged
    np.testing.assert_allclose(np.abs(r.rao["fish_heave"]), np.abs(r2.rao["fish_heave"]), rtol=3e-3)
    assert s.significant["fish_heave"] == pytest.approx(s2.significant["fish_heave"], rel=3e-3)
    # stochastic vs harmonic: at the same velocity scale the Gaussian damping exceeds the harmonic one
    # (√(8/π) σ with σ = A/√2 is 1.06 × 8A/(3π)), so the resonant heave is a little smaller, not wildly
    assert s.significant["fish_heave"] > 0


def test_tree_solver_matches_dense():
    lm = LinearModel("two_part_tow_1")
    om = np.linspace(0.1, 2.0, 12)
    a = lm.response(om, compensator={"stiffness": 1e4, "damping": 5e3, "mass": 100.0})
    lm.use_tree = False
    b = lm.response(om, compensator={"stiffness": 1e4, "damping": 5e3, "mass": 100.0})
    for k in ("fish_heave", "fish_pitch", "top_tension", "stroke", "depressor_heave"):
        np.testing.assert_allclose(a.rao[k], b.rao[k], rtol=1e-7, atol=1e-9 * np.abs(b.rao[k]).max())


def test_per_frequency_top_motion():
    """A (nf, 3) top amplitude gives, row by row, the same RAOs as separate calls (harmonic linearisation
    at each row's amplitude; frequencies are independent), to twice the 1e-3 fixed-point tolerance."""
    lm = LinearModel("two_part_tow_1")
    om = np.array([0.4, 0.9, 1.6])
    top = np.array([[0.3, 0.0, 1.0], [0.0, 0.0, 0.5j], [0.2, 0.1, 2.0]])
    r = lm.response(om, top=top)
    for i in range(3):
        ri = lm.response(om[i:i + 1], top=top[i])
        np.testing.assert_allclose(r.rao["fish_heave"][i], ri.rao["fish_heave"][0], rtol=2e-3)
        np.testing.assert_allclose(r.rao["top_tension"][i], ri.rao["top_tension"][0], rtol=2e-3)
    with pytest.raises(ValueError, match="top"):
        lm.response(om, top=np.ones((2, 3)))


def test_deterministic():
    lm = LinearModel("two_part_tow_1")
    om = np.linspace(0.1, 2.0, 9)
    a = lm.response(om)
    b = LinearModel("two_part_tow_1").response(om)
    for k in a.rao:
        assert np.array_equal(a.rao[k], b.rao[k])


# -------------------------------------------------------------------------------------------------
# spectral statistics and compensator tuning
# -------------------------------------------------------------------------------------------------
def test_spectral_tow_point_statistics(hover_planar):
    """With no vessel RAO the tow point heaves with the wave (stated in tow_point_model): its significant
    height is Hs up to the spectrum outside 0.3–4 ω_p (< 1 %)."""
    ss = SeaState(3.0, 9.0, spectrum="bretschneider")
    s = hover_planar.spectral(ss)
    assert "wave elevation" in s.tow_point_model
    assert s.significant["top_heave"] == pytest.approx(3.0, rel=0.01)
    assert s.highest_1000["fish_heave"] == pytest.approx(3.9662 / 4 * s.significant["fish_heave"], rel=1e-3)


def test_tune_compensator_grid(hover_planar):
    ss = SeaState.from_code(5, "open_ocean", spectrum="bretschneider")
    t = hover_planar.tune_compensator(ss, [1e3, 1e4, 1e5], [1e3, 1e4], stroke_limit=4.0, mass=530.0)
    assert t.fish_heave.shape == (3, 2) and np.all(np.isfinite(t.fish_heave))
    assert t.best is not None and t.best["stroke_1000"] <= 2.0
    assert t.best["fish_heave"] < t.locked["fish_heave"]
    # a stiffer spring means a smaller stroke
    assert np.all(np.diff(t.stroke, axis=0) < 0)


# -------------------------------------------------------------------------------------------------
# bad input
# -------------------------------------------------------------------------------------------------
def test_bad_input_is_named(hover_planar):
    with pytest.raises(ValueError, match="omega"):
        hover_planar.response([-0.1, 0.5])
    with pytest.raises(ValueError, match="omega"):
        hover_planar.response([0.0])
    with pytest.raises(ValueError, match="top"):
        hover_planar.response([0.5], top=(0, 0, 0))
    with pytest.raises(ValueError, match="drag"):
        hover_planar.response([0.5], drag="cubic")
    with pytest.raises(ValueError, match=r"compensator\.stiffness"):
        hover_planar.response([0.5], compensator={"stiffness": -1.0, "damping": 0.0})
    with pytest.raises(ValueError, match="sea_state"):
        hover_planar.spectral({"hs": 2.0})
    with pytest.raises(ValueError, match="stroke_limit"):
        hover_planar.tune_compensator(SeaState(2.0, 8.0), [1e4], [1e4], stroke_limit=0.0)
    r = hover_planar.response([0.5])
    with pytest.raises(KeyError, match="fish_heav.*available"):
        r.amplitude("fish_heav")
    with pytest.raises(KeyError, match="available"):
        r.rao["fish_heav"]
    with pytest.raises(ValueError, match="segments"):
        LinearModel("two_part_tow_1", segments=0)


def test_scenes_it_cannot_linearise():
    # an exactly neutrally buoyant cable with a free end carries no tension at all
    sc = _clump_scene()
    sc["bodies"] = []
    sc["lines"][0].update(bottom="free", mass_per_length=RHO * math.pi * 0.005 ** 2 / 4)
    with pytest.raises(LinearisationError, match="slack"):
        LinearModel(sc)
    d = H.load_scene("two_part_tow_1").to_dict()
    d["winch"] = {"mode": "speed", "speed": 0.0}
    with pytest.raises(LinearisationError, match="winch"):
        LinearModel(d)


def test_damped_modes_predict_the_lateral_instability_of_the_towfish():
    """hover_deep_tow at 2 m/s in calm water: the linearised model has a lateral (roll/yaw) mode with a
    positive growth rate σ; the nonlinear 3-D simulator, started in equilibrium with the towfish yawed by
    1e-12 rad, shows the same mode growing (the yaw envelope grows e^{100σ} ≈ 2e4-fold in 100 s) at the
    same rate. (The seed is explicit: the kernels compute exactly, so an exactly symmetric start stays in its
    plane; under fast-math the round-off seeded the mode.) Tolerance 2 %: the envelope fit over 100 s resolves σ to
    ~0.5 %, and Houbolt's numerical damping at ωΔt = 0.036 is ~1e-5/s."""
    from towenv.core.simulator import Simulator
    sc = load("hover_deep_tow").with_overrides({"vessel.speed": 2.0, "solver.dt": 0.02, "vessel.excitation": None})
    lam, frac = LinearModel(sc).damped_modes()
    assert lam[0].real > 0.05 and frac[0] > 0.99        # unstable, and lateral
    sim = Simulator(sc)
    sim.hist_ang[:, 0, 2] += 1e-12                       # the towfish yawed at rest (all history levels)
    n = int(round(160.0 / 0.02))
    yaw, t = np.empty(n), (np.arange(n) + 1) * 0.02
    for i in range(n):
        sim.advance_steps(1)
        yaw[i] = sim.body_state("towfish")["euler"][2]
    period = 2 * np.pi / abs(lam[0].imag)
    k = np.arange(int(60 / period), int(160 / period))
    env = np.array([np.max(np.abs(yaw[(t >= i * period) & (t < (i + 1) * period)])) for i in k])
    sigma = np.polyfit((k + 0.5) * period, np.log(env), 1)[0]
    assert sigma == pytest.approx(lam[0].real, rel=0.02)
    # at zero speed the same mode is neutral (|σ| at round-off level), and a conventional tow has none
    lam0, _ = LinearModel(load("hover_deep_tow")).damped_modes()
    assert abs(lam0[0].real) < 1e-6
    lamc, _ = LinearModel(load("conventional_tow")).damped_modes()
    assert lamc[0].real < -0.01


def _fish_added_mass(d, reference, coriolis):
    """two_part_tow_1's fish with its diagonal added mass given as a matrix about ``reference``."""
    for b in d["bodies"]:
        if b["name"] == "fish":
            M = np.diag(list(b["added_mass"]) + list(b["added_inertia"])).tolist()
            b.update(added_mass=[0.0] * 3, added_inertia=[0.0] * 3, added_mass_matrix=M,
                     added_mass_reference=list(reference), added_mass_coriolis=coriolis)
    return d


def test_off_centre_added_mass_in_the_linear_model_matches_time_domain():
    """Issue 18, item 1: the fish's added mass of two_part_tow_1 placed 0.4 m aft of the tow point (heave-pitch
    coupling A₂₁, +6 kg m² of pitch inertia about the tow point) changes the fish's heave and pitch RAOs at
    0.8 rad/s by more than 50 % (measured 0.153 → 0.271 m/m, 0.053 → 0.093 rad/m); the linear model follows
    the simulator within 5 % as for the diagonal case (measured ≤ 1 %)."""
    om = 0.8
    d = _fish_added_mass(H.load_scene("two_part_tow_1").to_dict(), (-0.4, 0.0, 0.0), False)
    r = LinearModel(d).response(np.array([om]), top=(0, 0, 0.2))
    base = LinearModel(H.load_scene("two_part_tow_1").to_dict()).response(np.array([om]), top=(0, 0, 0.2))
    td = _td_amplitudes(d, om, 0.2, "fish", "secondary")
    for k in ("fish_heave", "fish_pitch"):
        assert abs(r.rao[k][0]) > 1.5 * abs(base.rao[k][0]), k
    for k in ("fish_heave", "fish_pitch", "fish_tension", "top_tension"):
        assert abs(r.rao[k][0]) == pytest.approx(abs(td[k]), rel=0.05), k


def test_damped_modes_predict_the_munk_divergence():
    """two_part_tow_1 in calm water with the fish's added-mass Coriolis terms on (``added_mass_coriolis``): the
    Munk moment (A₃₃ − A₁₁) U² α ≈ 320 N m/rad at 3 m/s overcomes the fish's own restoring moment, and the
    linearised model has a real vertical-plane root σ > 0 (a static pitch divergence); the simulator, started in
    equilibrium with the fish pitched by 1e-9 rad, grows at the same rate (fit while |Δθ| is in 1e-7 … 1e-3 rad).
    Tolerance 2 %: Houbolt's error for a real root at σΔt ≈ 0.04 is below 1 % (measured 0.6 %). Without the
    terms the scene has no unstable root."""
    from towenv.core.simulator import Simulator
    d = load("two_part_tow_1").with_overrides({"vessel.excitation": None}).to_dict()
    lam_off, _ = LinearModel(load(d)).damped_modes()
    assert lam_off[0].real < 0.0
    for b in d["bodies"]:
        if b["name"] == "fish":
            b["added_mass_coriolis"] = True
    sc = load(d)
    lam, frac = LinearModel(sc).damped_modes()
    assert lam[0].real > 1.0 and abs(lam[0].imag) < 1e-9 and frac[0] < 1e-6       # real root, vertical plane
    sim = Simulator(sc)
    fish = next(b.rigid_index for b in sim.system.bodies if b.name == "fish")
    p0 = sim.body_state("fish")["euler"][1]
    sim.hist_ang[:, fish, 1] += 1e-9
    n = int(round(8.0 / sim.dt))
    dp, t = np.empty(n), (np.arange(n) + 1) * sim.dt
    for i in range(n):
        sim.advance_steps(1)
        dp[i] = abs(sim.body_state("fish")["euler"][1] - p0)
    m = (dp > 1e-7) & (dp < 1e-3)
    assert m.sum() > 50
    assert np.polyfit(t[m], np.log(dp[m]), 1)[0] == pytest.approx(lam[0].real, rel=0.02)
