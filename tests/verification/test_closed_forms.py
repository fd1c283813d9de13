"""Tests of the independent closed-form references against verification.md.

Tolerance policy: the expected values in ``shared/reference/verification.md``
and ``model.md`` are printed rounded, so :func:`assert_rounds_to` accepts a
computed value iff it lies within half a unit of the last printed digit
(i.e. it would print as the published number).  Property tests use tolerances
derived from the physics and are commented individually.
"""

from __future__ import annotations

import ast
import pathlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from towenv.verification import closed_forms as cf
from towenv.verification.closed_forms import PEER_DECK as DECK

M_EFF = DECK.M + DECK.M_a  # 602.5 kg: body mass + vertical added mass (V3)


def assert_rounds_to(value, printed, decimals):
    """Assert that ``value`` rounds to ``printed`` at ``decimals`` decimal places.

    Half a unit in the last printed place, plus 1e-9 of that unit for the
    floating-point representation of the printed number itself.
    """
    half_unit = 0.5 * 10.0 ** (-decimals)
    assert abs(value - printed) <= half_unit * (1 + 1e-9), (
        f"{value!r} does not round to {printed} ({decimals} decimals)"
    )


def steady_tow(U, L=DECK.L, EA=DECK.EA, CdA=DECK.CdA, W_b=DECK.W_b, **kw):
    return cf.steady_tow_ode(
        L, U, DECK.w, EA, D=DECK.D, Cn=DECK.Cn, Ct_dl=DECK.Ct_dl, rho=DECK.rho,
        CdA=CdA, W_b=W_b, **kw,
    )


# ---------------------------------------------------------------------------
# Hygiene: the reference must be independent of the simulator
# ---------------------------------------------------------------------------


def test_module_imports_only_numpy_scipy_and_stdlib():
    tree = ast.parse(pathlib.Path(cf.__file__).read_text())
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, "no relative imports"
            imported.add(node.module.split(".")[0])
    assert imported <= {"__future__", "dataclasses", "numpy", "scipy"}


# ---------------------------------------------------------------------------
# Peer deck derived quantities
# ---------------------------------------------------------------------------


def test_peer_deck_derived_quantities():
    # Printed: w = 6.6488 N/m, W_b = 3898.14 N, c_L = 4472 m/s.
    assert_rounds_to(DECK.w, 6.6488, 4)
    assert_rounds_to(DECK.W_b, 3898.14, 2)
    assert_rounds_to(DECK.c_L, 4472, 0)
    # MoorDyn's CdAx on pi*D*l equals Ct_dl/pi.
    assert DECK.Ct_dl == pytest.approx(np.pi * 0.01, rel=1e-15)


# ---------------------------------------------------------------------------
# V1. Vertical hang
# ---------------------------------------------------------------------------


def test_v1_vertical_hang():
    hang = cf.vertical_hang(DECK.w, DECK.L, DECK.W_b)
    assert_rounds_to(hang["top_reaction"], 4563.02, 2)
    assert hang["bottom_tension"] == DECK.W_b
    assert hang["tension"](DECK.L) == pytest.approx(hang["top_reaction"], rel=1e-15)
    # 20 segments: the top segment tension is w l/2 = 16.6 N below the reaction.
    seg = cf.segment_midpoint_tensions(DECK.w, DECK.L, DECK.W_b, 20)
    assert seg.shape == (20,)
    assert_rounds_to(hang["top_reaction"] - seg[-1], 16.6, 1)
    # MoorDyn's GetLineFairTen (top segment tension) printed as 4546.4 N, -3.6e-3.
    assert_rounds_to(seg[-1], 4546.4, 1)
    assert_rounds_to(seg[-1] / hang["top_reaction"] - 1, -3.6e-3, 4)


@given(n=st.integers(1, 500))
def test_v1_segment_tensions_are_midpoint_tensions(n):
    seg = cf.segment_midpoint_tensions(DECK.w, DECK.L, DECK.W_b, n)
    l = DECK.L / n
    # Exact up to round-off: the tension rises by w l per segment.
    np.testing.assert_allclose(np.diff(seg), DECK.w * l, rtol=1e-9)
    np.testing.assert_allclose(seg[0], DECK.W_b + DECK.w * l / 2, rtol=1e-14)


# ---------------------------------------------------------------------------
# V2. Elastic catenary
# ---------------------------------------------------------------------------


def test_v2_elastic_catenary_peer_cable():
    c = cf.elastic_catenary(DECK.L, DECK.w, DECK.EA, 80.0, 40.0)
    # Table values are printed to 0.01 N.
    assert_rounds_to(c.H, 290.49, 2)
    assert_rounds_to(c.V_A, -148.72, 2)
    assert_rounds_to(c.V_B, 516.16, 2)
    assert_rounds_to(c.T_top, 592.29, 2)
    assert_rounds_to(c.T_bottom, 326.34, 2)
    # The profile closes on B (solver tolerance, far below 1 um) and is consistent.
    assert c.x(DECK.L) == pytest.approx(80.0, abs=1e-8)
    assert c.z(DECK.L) == pytest.approx(40.0, abs=1e-8)
    x, z, T = c.shape(np.array([0.0, DECK.L]))
    assert x[0] == 0 and z[0] == 0
    np.testing.assert_allclose(T, [c.T_bottom, c.T_top], rtol=1e-14)
    # V_A < 0: the cable leaves A heading downward (sag vertex inside the span).
    assert c.z(1.0) < 0


def test_v2_catenary_profile_satisfies_its_ode():
    """dx/ds = (H/T + H/EA), dz/ds = ((V_A + w s)/T + (V_A + w s)/EA) (Irvine)."""
    c = cf.elastic_catenary(DECK.L, DECK.w, DECK.EA, 80.0, 40.0)
    s = np.linspace(1.0, 99.0, 50)
    h = 1e-4
    dxds = (c.x(s + h) - c.x(s - h)) / (2 * h)
    dzds = (c.z(s + h) - c.z(s - h)) / (2 * h)
    V = c.V_A + c.w * s
    # Central difference error ~ h^2 * x''' ~ 1e-8; round-off ~ 1e-16 * 100 / 1e-4.
    np.testing.assert_allclose(dxds, c.H / c.T(s) + c.H / c.EA, atol=1e-8)
    np.testing.assert_allclose(dzds, V / c.T(s) + V / c.EA, atol=1e-8)


@settings(max_examples=60, deadline=None)
@given(
    angle=st.floats(-1.3, 1.3),
    stretch=st.floats(1e-4, 1e-2),
)
def test_v2_catenary_tiny_weight_approaches_straight_line(angle, stretch):
    """With w -> 0 a taut elastic cable becomes a straight bar with T = EA (chord/L - 1)."""
    L, EA, w = 100.0, 2e7, 1e-4
    chord = L * (1 + stretch)
    x_B, z_B = chord * np.cos(angle), chord * np.sin(angle)
    c = cf.elastic_catenary(L, w, EA, x_B, z_B)
    T_bar = EA * stretch
    # Weight changes the tension by at most w L = 0.01 N along the cable.
    assert c.T_top == pytest.approx(T_bar, abs=w * L)
    assert c.T_bottom == pytest.approx(T_bar, abs=w * L)
    # Sag ~ w L^2 / (8 T) <= 1e-4 * 1e4 / (8 * 2e3) ~ 6e-5 m.
    s = np.linspace(0.0, L, 21)
    x, z = c.x(s), c.z(s)
    distance_from_chord = np.abs(x * z_B - z * x_B) / chord
    assert distance_from_chord.max() < 1e-4


@settings(max_examples=100, deadline=None)
@given(
    angle=st.floats(-1.5, 1.5),
    chord_over_L=st.floats(0.05, 1.01),
    log_w=st.floats(-3, 2),
    log_EA=st.floats(4, 9),
)
def test_v2_catenary_solver_is_robust(angle, chord_over_L, log_w, log_EA):
    L = 100.0
    x_B, z_B = L * chord_over_L * np.cos(angle), L * chord_over_L * np.sin(angle)
    c = cf.elastic_catenary(L, 10.0**log_w, 10.0**log_EA, x_B, z_B)
    # The solver accepts residuals below 1e-8 L = 1 um.
    assert c.x(L) == pytest.approx(x_B, abs=1e-6)
    assert c.z(L) == pytest.approx(z_B, abs=1e-6)
    assert c.H > 0


def test_v2_catenary_inextensible_limit():
    c_inf = cf.elastic_catenary(DECK.L, DECK.w, np.inf, 80.0, 40.0)
    c_big = cf.elastic_catenary(DECK.L, DECK.w, 1e14, 80.0, 40.0)
    # Stretch at EA = 1e14 is ~ 1e-11, so the two agree to ~1e-8 relative.
    assert c_inf.H == pytest.approx(c_big.H, rel=1e-7)
    assert c_inf.V_A == pytest.approx(c_big.V_A, rel=1e-7)


# ---------------------------------------------------------------------------
# V3. Axial string, end mass, compensator
# ---------------------------------------------------------------------------


def test_v3_axial_eigenfrequency_table():
    beta, omega = cf.axial_eigenfrequencies(DECK.L, DECK.mu, DECK.EA, M_EFF, n_modes=3)
    f = omega / (2 * np.pi)
    # Digits as printed in the V3 table.
    for b, b_ref in zip(beta, [0.39647, 3.19352, 6.30948]):
        assert_rounds_to(b, b_ref, 5)
    assert_rounds_to(omega[0], 17.73, 2)
    assert_rounds_to(omega[1], 142.8, 1)
    assert_rounds_to(omega[2], 282.2, 1)
    for fk, f_ref in zip(f, [2.822, 22.73, 44.91]):
        decimals = len(str(f_ref).split(".")[1])
        assert_rounds_to(fk, f_ref, decimals)
    # m L / M_eff printed as 0.166; spring-mass estimate printed as 17.74 rad/s.
    assert_rounds_to(DECK.mu * DECK.L / M_EFF, 0.166, 3)
    assert_rounds_to(cf.axial_spring_mass_frequency(DECK.L, DECK.mu, DECK.EA, M_EFF), 17.74, 2)


def test_v3_eigenfrequency_limits():
    # Heavy end mass: the first mode tends to the spring-mass frequency, with
    # relative error O((mL/M)^2).
    _, omega = cf.axial_eigenfrequencies(100.0, 1.0, 2e7, 1e6, 1)
    assert omega[0] == pytest.approx(cf.axial_spring_mass_frequency(100.0, 1.0, 2e7, 1e6), rel=1e-9)
    # No end mass: quarter-wave string, beta_k = (k - 1/2) pi.
    beta, _ = cf.axial_eigenfrequencies(100.0, 1.0, 2e7, 0.0, 4)
    np.testing.assert_allclose(beta, (np.arange(4) + 0.5) * np.pi, rtol=1e-15)
    # Tiny end mass: roots approach (k - 1/2) pi from below.
    beta, _ = cf.axial_eigenfrequencies(100.0, 1.0, 2e7, 1e-9, 4)
    np.testing.assert_allclose(beta, (np.arange(4) + 0.5) * np.pi, rtol=1e-9)
    # Each root satisfies beta tan(beta) = m L / M (to root-finder precision).
    beta, _ = cf.axial_eigenfrequencies(DECK.L, DECK.mu, DECK.EA, M_EFF, 10)
    np.testing.assert_allclose(beta * np.tan(beta), DECK.mu * DECK.L / M_EFF, rtol=1e-9)
    assert np.all(np.diff(beta) > 0)


def test_v3_low_frequency_limits_of_tensions():
    """omega -> 0: T_1 -> -(M + M_a) omega^2 p_n and T_n -> -(M + M_a + m L) omega^2 p_n."""
    omega = np.array([1e-4, 1e-3, 1e-2, 1e-1])
    tf = cf.axial_string_tf(omega, DECK.L, DECK.mu, DECK.EA, M_EFF)
    # Leading correction is O((omega/omega_1)^2) <= (0.1/17.7)^2 ~ 3e-5.
    np.testing.assert_allclose(tf.T1, -M_EFF * omega**2, rtol=1e-4)
    np.testing.assert_allclose(tf.Tn, -(M_EFF + DECK.mu * DECK.L) * omega**2, rtol=1e-4)
    np.testing.assert_allclose(tf.p1, 1.0, rtol=1e-4)
    # Exactly at omega = 0 the string moves rigidly with zero dynamic tension.
    tf0 = cf.axial_string_tf(0.0, DECK.L, DECK.mu, DECK.EA, M_EFF)
    assert tf0.p1 == 1 and tf0.T1 == 0 and tf0.Tn == 0


def test_v3_no_end_mass_gives_zero_body_tension():
    omega = np.linspace(0.1, 300, 50)
    tf = cf.axial_string_tf(omega, DECK.L, DECK.mu, DECK.EA, 0.0, b_p=0.5)
    assert np.all(tf.T1 == 0)


def test_v3_tension_tf_at_ends_matches_string_tf():
    omega = np.linspace(0.0, 300.0, 61)
    args = (DECK.L, DECK.mu, DECK.EA, M_EFF, 300.0, 0.7)
    tf = cf.axial_string_tf(omega, *args)
    T_at = lambda s: cf.axial_string_tension_tf(omega, s, *args)  # noqa: E731
    P_at = lambda s: cf.axial_string_displacement_tf(omega, s, *args)  # noqa: E731
    # Same closed form evaluated two ways: agreement to round-off.
    np.testing.assert_allclose(T_at(0.0), tf.T1, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(T_at(DECK.L), tf.Tn, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(P_at(0.0), tf.p1, rtol=1e-12)
    np.testing.assert_allclose(P_at(DECK.L), 1.0, rtol=1e-12)
    # Broadcasting omega against s.
    grid = cf.axial_string_tension_tf(omega[:, None], np.array([0.0, DECK.L]), *args)
    assert grid.shape == (61, 2)


def test_v3_resonance_at_first_eigenfrequency():
    _, omega = cf.axial_eigenfrequencies(DECK.L, DECK.mu, DECK.EA, M_EFF, 1)
    near = omega[0] * np.array([1 - 1e-9, 1 + 1e-9])
    tf = cf.axial_string_tf(near, DECK.L, DECK.mu, DECK.EA, M_EFF)
    # Undamped: the response diverges and changes sign across the resonance.
    assert np.all(np.abs(tf.p1) > 1e6)
    assert np.sign(tf.p1[0].real) != np.sign(tf.p1[1].real)


@pytest.mark.parametrize("B_Q, b_p", [(0.0, 0.0), (500.0, 2.0)])
@pytest.mark.parametrize("omega", [0.5, 5.0, 17.0, 30.0, 100.0, 150.0])
def test_v3_string_tf_matches_2000_segment_lumped_chain(omega, B_Q, b_p):
    """V3 states: relative differences below 3e-6 with tensions at segment midpoints."""
    n = 2000
    l = DECK.L / n
    args = (DECK.L, DECK.mu, DECK.EA, M_EFF, B_Q, b_p)
    tf = cf.axial_string_tf(omega, *args)
    u, T = cf.lumped_axial_chain_tf(omega, n, DECK.L, DECK.mu, DECK.EA, M_EFF, B_Q, b_p)
    T_mid = cf.axial_string_tension_tf(omega, np.array([l / 2, DECK.L - l / 2]), *args)
    assert abs(u[0] / tf.p1 - 1) < 3e-6
    assert abs(T[0] / T_mid[0] - 1) < 3e-6
    assert abs(T[-1] / T_mid[1] - 1) < 3e-6


@settings(max_examples=50, deadline=None)
@given(
    omega=st.floats(0.01, 300.0),
    b_c=st.floats(0.0, 1e5),
    m_c=st.floats(0.0, 1e3),
    B_Q=st.floats(0.0, 1e3),
)
def test_v3_stiff_compensator_equals_locked_string(omega, b_c, m_c, B_Q):
    args = (DECK.L, DECK.mu, DECK.EA, M_EFF)
    locked = cf.axial_string_tf(omega, *args, B_Q=B_Q, b_p=0.1)
    comp = cf.compensator_tf(omega, *args, k_c=1e16, b_c=b_c, m_c=m_c, B_Q=B_Q, b_p=0.1)
    # |Delta_11 - omega^2 m_c| / k_c is the relative error; with k_c = 1e16 it is
    # tiny except right at an undamped string resonance, where the dynamic
    # stiffness diverges: hence the 1e-6 tolerance.
    np.testing.assert_allclose(comp.pn, 1.0, rtol=1e-6)
    np.testing.assert_allclose(comp.p1, locked.p1, rtol=1e-6)
    np.testing.assert_allclose(comp.T1, locked.T1, rtol=1e-6)
    np.testing.assert_allclose(comp.Tn, locked.Tn, rtol=1e-6)
    exact = cf.compensator_tf(omega, *args, k_c=np.inf, B_Q=B_Q, b_p=0.1)
    assert exact.pn == 1 and exact.R == 0 and exact.T1 == locked.T1


def test_v3_compensator_basic_properties():
    omega = np.linspace(0.05, 50, 200)
    args = (DECK.L, DECK.mu, DECK.EA, M_EFF)
    comp = cf.compensator_tf(omega, *args, k_c=2e4, b_c=5e3, m_c=100.0, B_Q=200.0)
    np.testing.assert_allclose(comp.R, comp.pn - 1.0, rtol=0, atol=1e-15)
    # Soft compensator well above its own natural frequency isolates the cable top.
    soft = cf.compensator_tf(np.array([20.0]), *args, k_c=1.0, b_c=0.0)
    assert abs(soft.pn[0]) < 1e-3
    # Dynamic equilibrium of the top: k_c (D - p_n) + j w b_c (D - p_n) = T_n - w^2 m_c p_n.
    z_c = 2e4 + 1j * omega * 5e3
    np.testing.assert_allclose(
        z_c * (1 - comp.pn), comp.Tn - omega**2 * 100.0 * comp.pn, rtol=1e-10
    )


# ---------------------------------------------------------------------------
# V4. Wave speeds and lumped chains
# ---------------------------------------------------------------------------


def test_v4_wave_speeds_and_taut_string():
    c_T = cf.transverse_wave_speed(4563.0, DECK.mu, DECK.D, DECK.rho, DECK.Can)
    assert_rounds_to(c_T, 58.75, 2)
    assert_rounds_to(cf.taut_string_period(DECK.L, c_T), 3.40, 2)
    # 20 segments: l / c_L printed as 1.12 ms.
    assert_rounds_to(5.0 / DECK.c_L * 1e3, 1.12, 2)


def test_v4_dispersion_cutoff_and_continuum_limit():
    c, l = 50.0, 2.0
    assert cf.lumped_chain_dispersion(np.pi / l, l, c) == pytest.approx(2 * c / l, rel=1e-15)
    # omega / (c k) = 1 - (kl)^2/24 + ...: check the O((kl)^2) convergence.
    kl = np.array([0.1, 0.05])
    ratio = cf.lumped_chain_dispersion(kl / l, l, c) / (c * kl / l)
    np.testing.assert_allclose(1 - ratio, kl**2 / 24, rtol=1e-2)


@pytest.mark.parametrize("n", [1, 2, 5, 20, 100])
def test_v4_lumped_axial_chain_without_end_mass_obeys_dispersion(n):
    """A free-end chain with a half-mass end node is the symmetric half of a 2n
    fixed-fixed chain, so its modes sit exactly at k = (j - 1/2) pi / L."""
    omega = cf.lumped_axial_chain_eigenfrequencies(n, DECK.L, DECK.mu, DECK.EA, 0.0)
    k = (np.arange(n) + 0.5) * np.pi / DECK.L
    expected = cf.lumped_chain_dispersion(k, DECK.L / n, DECK.c_L)
    np.testing.assert_allclose(omega, expected, rtol=1e-10)  # eigh round-off


def test_v4_lumped_axial_chain_converges_to_continuous_modes():
    _, omega_exact = cf.axial_eigenfrequencies(DECK.L, DECK.mu, DECK.EA, M_EFF, 3)
    errors = []
    for n in (20, 40, 80):
        omega = cf.lumped_axial_chain_eigenfrequencies(n, DECK.L, DECK.mu, DECK.EA, M_EFF)
        errors.append(np.abs(omega[:3] / omega_exact - 1))
    errors = np.array(errors)
    # Second-order spatial convergence: halving l quarters the error.
    np.testing.assert_allclose(errors[:-1] / errors[1:], 4.0, rtol=0.05)
    free = cf.lumped_axial_chain_eigenfrequencies(
        20, DECK.L, DECK.mu, DECK.EA, M_EFF, top_fixed=False
    )
    assert free.shape == (21,) and free[0] < 1e-3


# ---------------------------------------------------------------------------
# V5. Hanging chain, V6. Pendulum
# ---------------------------------------------------------------------------


def test_v5_hanging_chain_periods():
    air = cf.hanging_chain_periods(100.0, DECK.g, 3)
    for T, T_ref in zip(air, [16.69, 7.27, 4.64]):
        assert_rounds_to(T, T_ref, 2)
    g_eff = cf.g_eff_cable(DECK.mu, DECK.D, DECK.rho, DECK.g, DECK.Can)
    assert_rounds_to(g_eff, 5.029, 3)
    water = cf.hanging_chain_periods(100.0, g_eff, 3)
    for T, T_ref in zip(water, [23.30, 10.15, 6.48]):
        assert_rounds_to(T, T_ref, 2)
    # Bessel zeros as printed.
    j0 = 2 * np.pi / cf.hanging_chain_periods(1.0, 4.0, 4)  # omega = j0 when g/L = 4
    for j, j_ref in zip(j0, [2.40483, 5.52008, 8.65373, 11.79153]):
        assert_rounds_to(j, j_ref, 5)


def test_v6_pendulum_period():
    assert_rounds_to(cf.g_eff_body(DECK.M, DECK.V, DECK.Ca, DECK.rho, DECK.g), 6.470, 3)
    assert_rounds_to(cf.pendulum_period(100.0, DECK.M, DECK.V, DECK.Ca, DECK.rho, DECK.g), 24.70, 2)
    in_air = cf.pendulum_period(100.0, DECK.M)
    assert in_air == pytest.approx(2 * np.pi * np.sqrt(100.0 / DECK.g), rel=1e-15)
    assert cf.pendulum_period(100.0, DECK.M, DECK.V, DECK.Ca, rho=0.0) == in_air


# ---------------------------------------------------------------------------
# V7. Steady tow and critical angle
# ---------------------------------------------------------------------------

V7_TABLE = [
    # U, top tension (N), top angle (deg), behind (m), below (m)
    (0.5, 4562.6, 85.35, 5.05, 99.88),
    (1.0, 4558.1, 72.01, 19.67, 97.81),
    (2.0, 4601.9, 38.87, 58.92, 78.78),
    (3.0, 5092.8, 22.27, 81.44, 55.37),
]


@pytest.mark.parametrize("U, T_top, angle, behind, below", V7_TABLE)
def test_v7_steady_tow_table(U, T_top, angle, behind, below):
    sol = steady_tow(U)
    # Printed to 0.1 N, 0.01 deg and 0.01 m.
    assert_rounds_to(sol.top_tension, T_top, 1)
    assert_rounds_to(sol.top_angle_deg, angle, 2)
    assert_rounds_to(sol.body_behind, behind, 2)
    assert_rounds_to(sol.body_below, below, 2)


@pytest.mark.parametrize("U", [0.5, 1.0, 2.0, 3.0])
def test_v7_inextensible_variant(U):
    elastic, rigid = steady_tow(U), steady_tow(U, EA=np.inf)
    # "The same tensions": the tension ODE does not depend on stretch (to
    # integrator tolerance, rtol 1e-10).
    assert rigid.top_tension == pytest.approx(elastic.top_tension, rel=1e-9)
    assert rigid.top_angle_deg == pytest.approx(elastic.top_angle_deg, rel=1e-9)
    # "About 1-3 cm shorter in depth": the stretch T L / EA is at most ~2.5 cm.
    assert 0.005 < elastic.body_below - rigid.body_below < 0.03
    # Arc length of the inextensible cable is exactly L.
    ds = np.hypot(np.diff(rigid.x), np.diff(rigid.z))
    assert ds.sum() == pytest.approx(DECK.L, rel=1e-4)  # chord sum under-estimates arc length


def test_v7_inextensible_at_2_m_s():
    sol = steady_tow(2.0, EA=np.inf)
    assert_rounds_to(sol.body_behind, 58.91, 2)
    assert_rounds_to(sol.body_below, 78.77, 2)


def test_v7_no_body_drag_at_2_m_s():
    sol = steady_tow(2.0, CdA=0.0)
    assert_rounds_to(sol.top_tension, 4502.1, 1)
    assert_rounds_to(sol.body_behind, 45.40, 2)
    assert_rounds_to(sol.body_below, 86.01, 2)
    # The ignored-drag-area peer error: printed as 2.2 % low in tension.
    assert_rounds_to(100 * (1 - sol.top_tension / steady_tow(2.0).top_tension), 2.2, 1)


def test_v7_critical_angle_table():
    phi = cf.critical_angle(DECK.w, DECK.rho, DECK.Cn, DECK.D, [0.5, 1.0, 2.0, 3.0])
    for p, p_ref in zip(phi, [66.9, 40.0, 20.8, 14.0]):
        assert_rounds_to(p, p_ref, 1)
    # Defining balance w cos(phi) = R sin^2(phi).
    R = 0.5 * DECK.rho * DECK.Cn * DECK.D * np.array([0.5, 1.0, 2.0, 3.0]) ** 2
    r = np.radians(phi)
    np.testing.assert_allclose(DECK.w * np.cos(r), R * np.sin(r) ** 2, rtol=1e-12)
    assert cf.critical_angle(DECK.w, DECK.rho, DECK.Cn, DECK.D, 0.0) == 90.0


@pytest.mark.parametrize("U, angle", [(1.0, 40.04), (2.0, 20.82), (3.0, 13.97)])
def test_v7_long_cable_reaches_critical_angle(U, angle):
    """1 km peer cable, negligible body (10 kg, CdA 0.01 m^2; volume taken as 0)."""
    sol = steady_tow(U, L=1000.0, CdA=0.01, W_b=cf.body_wet_weight(10.0, 0.0))
    assert_rounds_to(sol.top_angle_deg, angle, 2)
    phi_c = cf.critical_angle(DECK.w, DECK.rho, DECK.Cn, DECK.D, U)
    assert abs(sol.top_angle_deg - phi_c) < 0.01
    # Straight part: dT/ds = w sin(phi_c) + 1/2 rho Ct' D U^2 cos^2(phi_c).
    r = np.radians(phi_c)
    dTds = DECK.w * np.sin(r) + 0.5 * DECK.rho * DECK.Ct_dl * DECK.D * U**2 * np.cos(r) ** 2
    assert np.gradient(sol.T, sol.s)[-1] == pytest.approx(dTds, rel=1e-4)


def test_v7_body_force_argument_is_equivalent():
    U = 2.0
    F0 = (0.5 * DECK.rho * DECK.CdA * U**2, DECK.W_b)
    a = steady_tow(U)
    b = steady_tow(U, CdA=123.0, W_b=-7.0, body_force=F0)  # body_force overrides
    assert b.top_tension == a.top_tension and b.body_below == a.body_below
    # A lifting body: less net downward force gives a shallower body.
    lifted = steady_tow(U, body_force=(F0[0], 0.5 * F0[1]))
    assert lifted.body_below < a.body_below


def test_v7_zero_speed_is_the_vertical_hang():
    sol = steady_tow(0.0)
    hang = cf.vertical_hang(DECK.w, DECK.L, DECK.W_b)
    assert sol.top_tension == pytest.approx(hang["top_reaction"], rel=1e-12)
    assert sol.top_angle_deg == pytest.approx(90.0, abs=1e-12)
    assert sol.body_behind == pytest.approx(0.0, abs=1e-12)
    # Stretch: integral of T/EA ds = (W_b L + w L^2 / 2)/EA.
    stretch = (DECK.W_b * DECK.L + 0.5 * DECK.w * DECK.L**2) / DECK.EA
    assert sol.body_below == pytest.approx(DECK.L + stretch, rel=1e-12)


# ---------------------------------------------------------------------------
# model.md 8.1 / V9. Houbolt
# ---------------------------------------------------------------------------


def test_houbolt_ad_pe_table():
    # model.md 8.1 Houbolt column, AD % / PE %, at the printed digits.
    table = [
        (0.01, 0.08, 0.18, 2),
        (0.02, 0.58, 0.70, 2),
        (0.05, 6.8, 3.9, 1),
        (0.10, 26.5, 12.3, 1),
        (0.20, 54.6, 34.4, 1),
        (0.30, 65.3, 60.3, 1),
    ]
    ratios = np.array([row[0] for row in table])
    ad, pe = cf.houbolt_ad_pe(ratios)
    for (_, ad_ref, pe_ref, decimals), a, p in zip(table, ad, pe):
        assert_rounds_to(100 * a, ad_ref, decimals)
        assert_rounds_to(100 * p, pe_ref, decimals)


def test_houbolt_spectral_radius_table():
    ratios = [0.01, 0.05, 0.10, 0.20, 0.30, 0.50, 1, 10, 100]
    printed = [1.0000, 0.9965, 0.9697, 0.8539, 0.7279, 0.5458, 0.3392, 0.0659, 0.0138]
    for rho, rho_ref in zip(cf.houbolt_spectral_radius(ratios), printed):
        assert_rounds_to(rho, rho_ref, 4)


def test_houbolt_asymptotics():
    # PE ~ (11/24)(omega dt)^2 and damping ratio ~ (omega dt)^3 / 2 for small dt.
    r = 1e-3
    Omega = 2 * np.pi * r
    ad, pe = cf.houbolt_ad_pe(r)
    assert pe == pytest.approx(11 / 24 * Omega**2, rel=1e-2)
    # AD over one period = 1 - exp(-2 pi xi) ~ 2 pi xi.
    assert ad == pytest.approx(2 * np.pi * 0.5 * Omega**3, rel=1e-2)
    # The spurious root tends to 0.5.
    eig = np.linalg.eigvals(cf.houbolt_amplification_matrix(1e-4))
    spurious = eig[np.argmin(np.abs(eig.imag) + np.abs(np.abs(eig) - 0.5))]
    assert spurious.real == pytest.approx(0.5, abs=1e-3)
