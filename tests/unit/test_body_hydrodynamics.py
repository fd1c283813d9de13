"""Rigid-body hydrodynamics of the towed bodies (issue 18, item 1): a full 6×6 added mass given about any point,
and the added mass's Coriolis/centripetal terms with the Munk moment (``added_mass_coriolis``).

* a free body with no damping in still water keeps its kinetic energy ½ νᵀ(M_RB + M_A)ν with the Kirchhoff terms
  (and does not without them: the check can fail);
* the same added mass given about two different points (and about the tow point) gives the same parameters and
  the same motion to round-off;
* closed forms: the pitch acceleration and the effective heave mass of a body whose heave added mass sits off the
  tow point under a prescribed heave acceleration (a point added mass at x_P: θ̈ = x_P A₃₃ a_z / (I + x_P² A₃₃));
  the Munk moment (A₃₃ − A₁₁) u w of a steady body at incidence;
* bad matrices are refused naming the field.
"""
from __future__ import annotations

import copy

import numpy as np
import pytest

from towenv.core import kernels as K
from towenv.core.system import MAX_TABLE, _rigid_body_params, added_mass_about_tow_point
from towenv.scene import SceneError, load_scene
from towenv.scene.schema import RigidBody

from twin_cases import EXCITATION, FISH_ADDED_MASS_MATRIX, _simulator, kirchhoff_scene

ZERO_TABLE = dict(incidence_deg=[-90.0, 90.0], drag=[0.0, 0.0], lift=[0.0, 0.0], moment=[0.0, 0.0])


def _body(**kw):
    d = dict(name="fish", kind="fish", mass=100.0, volume=0.0976, inertia=[5.0, 20.0, 22.0], cg=[0.1, 0.02, -0.05],
             reference_area=0.1, reference_length=1.5, coefficients=ZERO_TABLE, rotational_damping=[0.0, 0.0, 0.0],
             quadratic_rotational_damping=[0.0, 0.0, 0.0])
    d.update(kw)
    return RigidBody(**d)


def _tables():
    btab_n = np.array([[2, 2]], np.int64)
    btab = np.zeros((1, 8, MAX_TABLE))
    btab[0, 0, :2] = btab[0, 4, :2] = (-90.0, 90.0)
    return btab_n, btab


def _mass6(bp):
    att, atr, arr = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    K.body_mass_blocks(0, bp, att, atr, arr)
    return np.block([[att, atr], [atr.T, arr]])


class _FreeBody:
    """A body alone in still water (no cable, no weight, no damping): the kernels' loads and condensation."""

    def __init__(self, body):
        self.bp = _rigid_body_params(body)[None, :]
        self.btab_n, self.btab = _tables()
        self.s = {k: np.zeros((3, 3)) for k in ("att", "atr", "arr", "arrinv", "aeff", "X")}
        self.v3 = {k: np.zeros(3) for k in ("f", "m", "hvec", "tmp3", "y", "tail")}

    def rates(self, v_g, R, w, cur=np.zeros(3)):
        lam = np.ascontiguousarray(R.T)
        f, m = self.v3["f"], self.v3["m"]
        K.body_loads(0, lam, lam @ v_g, w, self.bp, self.btab_n, self.btab, 1025.0, 0.0, cur, f, m, np.zeros(1))
        mnode, fnode = np.zeros((1, 3, 3)), np.zeros((1, 3))
        s, v = self.s, self.v3
        assert K.condense_body(0, 0, False, lam, w, v["tail"], self.bp, f, m, s["att"], s["atr"], s["arr"],
                               s["arrinv"], v["hvec"], v["tmp3"], s["aeff"], s["X"], v["y"], mnode, fnode)
        a_g = np.linalg.solve(mnode[0], fnode[0])
        return a_g, v["y"] - s["X"] @ (lam @ a_g)

    def energy(self, v_g, R, w):
        nu = np.r_[R.T @ v_g, w]
        return 0.5 * nu @ _mass6(self.bp) @ nu

    def run(self, seconds, dt=2e-3):
        """RK4 on (v_global, R, ω), R re-orthonormalised each step; returns the kinetic energy every step."""
        def skew(a):
            return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])

        def deriv(x):
            v_g, R, w = x
            a_g, wd = self.rates(v_g, R, w)
            return a_g, R @ skew(w), wd

        x = (np.array([1.0, 0.2, -0.3]), np.eye(3), np.array([0.3, -0.5, 0.4]))
        energies = [self.energy(*x)]
        for _ in range(int(round(seconds / dt))):
            k1 = deriv(x)
            k2 = deriv(tuple(a + 0.5 * dt * b for a, b in zip(x, k1)))
            k3 = deriv(tuple(a + 0.5 * dt * b for a, b in zip(x, k2)))
            k4 = deriv(tuple(a + dt * b for a, b in zip(x, k3)))
            x = tuple(a + dt / 6.0 * (b + 2 * c + 2 * d + e) for a, b, c, d, e in zip(x, k1, k2, k3, k4))
            u, _, vt = np.linalg.svd(x[1])
            x = (x[0], u @ vt, x[2])
            energies.append(self.energy(*x))
        return np.array(energies)


FULL = dict(added_mass_matrix=FISH_ADDED_MASS_MATRIX, added_mass_reference=[-0.4, 0.05, 0.1])


@pytest.mark.parametrize("added", [dict(added_mass=[10.0, 80.0, 120.0], added_inertia=[1.0, 30.0, 25.0]), FULL],
                         ids=["diagonal", "full_matrix_off_centre"])
def test_free_body_keeps_its_kinetic_energy_with_the_kirchhoff_terms(added):
    """No damping, still water, no weight: T = ½ νᵀ(M_RB + M_A)ν is an invariant of Kirchhoff's equations. RK4 at
    2 ms over 8 s of a tumbling body (ω ~ 0.7 rad/s, unequal added masses): measured drift ~1e-12 relative; bound
    1e-8. Without the Coriolis/centripetal terms of the added mass (the default, for tables that already hold the
    Munk moment) the same body's energy changes by more than 1 %: the test can fail."""
    with_terms = _FreeBody(_body(**added, added_mass_coriolis=True)).run(8.0)
    drift = np.max(np.abs(with_terms / with_terms[0] - 1.0))
    assert drift < 1e-8, drift
    without = _FreeBody(_body(**added, added_mass_coriolis=False)).run(8.0)
    assert np.max(np.abs(without / without[0] - 1.0)) > 1e-2


def _transfer_jacobian(d):
    """ν_P = J ν_O for a point at d from O: v_P = v + ω × d, computed with np.cross column by column."""
    J = np.zeros((6, 6))
    for k in range(6):
        e = np.zeros(6)
        e[k] = 1.0
        J[:3, k] = e[:3] + np.cross(e[3:], d)
        J[3:, k] = e[3:]
    return J


def test_added_mass_moved_to_the_tow_point_keeps_the_kinetic_energy():
    """M_tow point = Hᵀ M_r H (towenv.core.system) against the kinetic energy written with np.cross."""
    rng = np.random.default_rng(4)
    r = np.array([-0.4, 0.05, 0.1])
    b = _body(added_mass_matrix=FISH_ADDED_MASS_MATRIX, added_mass_reference=list(r))
    M_O = added_mass_about_tow_point(b)
    J = _transfer_jacobian(r)
    for _ in range(20):
        nu = rng.standard_normal(6)
        assert nu @ M_O @ nu == pytest.approx((J @ nu) @ np.array(FISH_ADDED_MASS_MATRIX) @ (J @ nu), rel=1e-12)


def _about(M_P, r_P, r_Q):
    """The added mass M_P given about r_P, re-expressed about r_Q (the test's own transfer)."""
    J = _transfer_jacobian(np.asarray(r_P) - np.asarray(r_Q))
    return (J.T @ np.asarray(M_P) @ J).tolist()


def test_added_mass_given_about_different_points_gives_the_same_motion():
    """The fish's added mass of the twin's Kirchhoff scene given about (−0.5, 0, 0), about (0.3, −0.1, 0.2) and about
    the tow point: the bodies' parameters agree to 1e-12 and 10 s of excited two-part tow (Houbolt, 500 steps) to
    1e-9 relative (node positions, body angles and tensions of the last step; round-off of the different
    transfers only)."""
    base = kirchhoff_scene(excitation=EXCITATION)
    r_P = base["bodies"][0]["added_mass_reference"]
    runs, bps = [], []
    for r_Q in (r_P, [0.3, -0.1, 0.2], [0.0, 0.0, 0.0]):
        sc = copy.deepcopy(base)
        sc["bodies"][0]["added_mass_matrix"] = _about(FISH_ADDED_MASS_MATRIX, r_P, r_Q)
        sc["bodies"][0]["added_mass_reference"] = list(r_Q)
        sim = _simulator(sc)
        bps.append(sim.system.bp.copy())
        sim.advance(10.0)
        runs.append(np.r_[sim.hist_r[0].ravel(), sim.hist_ang[0].ravel(), sim.tens_hist[0]])
    scale = np.max(np.abs(bps[0]))
    for bp, run in zip(bps[1:], runs[1:]):
        assert np.max(np.abs(bp - bps[0])) <= 1e-12 * scale
        assert np.max(np.abs(run - runs[0])) <= 1e-9 * np.max(np.abs(runs[0]))


@pytest.mark.parametrize("x_p", [-0.6, 0.8])
def test_off_centre_heave_added_mass_couples_heave_into_pitch(x_p):
    """A heave added mass A₃₃ concentrated at P = (x_P, 0, 0) of a body whose centre of mass is at the tow point,
    under a prescribed heave acceleration a_z (no rotation yet): the fluid pushes −A₃₃ (a_z − x_P θ̈) at P, so
    I θ̈ = x_P A₃₃ (a_z − x_P θ̈), θ̈ = x_P A₃₃ a_z / (I + x_P² A₃₃), and the tow point feels the effective heave
    mass m + A₃₃ − (x_P A₃₃)² / (I + x_P² A₃₃). The condensation's X, y and A_eff against these to 1e-12."""
    m, I_yy, A33, a_z = 100.0, 20.0, 150.0, 1.7
    M_P = np.zeros((6, 6))
    M_P[2, 2] = A33
    b = _body(mass=m, cg=[0.0, 0.0, 0.0], inertia=[5.0, I_yy, 22.0], added_mass_matrix=M_P.tolist(),
              added_mass_reference=[x_p, 0.0, 0.0], added_mass_coriolis=True)
    fb = _FreeBody(b)
    f, mm = np.zeros(3), np.zeros(3)
    s, v = fb.s, fb.v3
    mnode, fnode = np.zeros((1, 3, 3)), np.zeros((1, 3))
    assert K.condense_body(0, 0, False, np.eye(3), np.zeros(3), v["tail"], fb.bp, f, mm, s["att"], s["atr"],
                           s["arr"], s["arrinv"], v["hvec"], v["tmp3"], s["aeff"], s["X"], v["y"], mnode, fnode)
    theta_dd = (v["y"] - s["X"] @ np.array([0.0, 0.0, a_z]))[1]
    assert theta_dd == pytest.approx(x_p * A33 * a_z / (I_yy + x_p ** 2 * A33), rel=1e-12)
    m_eff = m + A33 - (x_p * A33) ** 2 / (I_yy + x_p ** 2 * A33)
    assert mnode[0, 2, 2] == pytest.approx(m_eff, rel=1e-12)
    assert mnode[0, 0, 0] == pytest.approx(m, rel=1e-12)


def test_munk_moment_of_a_steady_body_at_incidence():
    """Steady relative velocity v = U (cos α, 0, sin α), ω = 0, zero coefficient tables and no weight: the only
    moment is the Munk moment −v × (A₁₁ v), M_y = (A₃₃ − A₁₁) U² sin α cos α (destabilising: it turns the body
    broadside), and no force; none without ``added_mass_coriolis``."""
    A11, A33, U = 10.0, 120.0, 2.5
    btab_n, btab = _tables()
    for on in (True, False):
        bp = _rigid_body_params(_body(added_mass=[A11, 80.0, A33], added_inertia=[1.0, 30.0, 25.0],
                                      added_mass_coriolis=on))[None, :]
        for alpha in np.radians([-20.0, 5.0, 30.0]):
            f, mo = np.zeros(3), np.zeros(3)
            vb = U * np.array([np.cos(alpha), 0.0, np.sin(alpha)])
            K.body_loads(0, np.eye(3), vb, np.zeros(3), bp, btab_n, btab, 1025.0, 0.0, np.zeros(3), f, mo, np.zeros(1))
            munk = (A33 - A11) * U * U * np.sin(alpha) * np.cos(alpha) if on else 0.0
            assert mo[1] == pytest.approx(munk, rel=1e-12, abs=1e-12)
            assert np.max(np.abs(f)) < 1e-12 and abs(mo[0]) < 1e-12 and abs(mo[2]) < 1e-12


def _scene_with_fish(**fish):
    d = load_scene("two_part_tow_1").to_dict()
    for b in d["bodies"]:
        if b["kind"] == "fish":
            b.update(fish)
    return d


@pytest.mark.parametrize("fish, field, words", [
    (dict(added_mass_matrix=[[1.0] * 6] * 5), "added_mass_matrix", "6x6"),
    (dict(added_mass=[0.0, 0.0, 0.0], added_inertia=[0.0, 0.0, 0.0],
          added_mass_matrix=(np.eye(6) + np.eye(6, k=1)).tolist()), "added_mass_matrix[0][1]", "symmetric"),
    (dict(added_mass=[0.0, 0.0, 0.0], added_inertia=[0.0, 0.0, 0.0],
          added_mass_matrix=np.diag([1.0, 1, 1, 1, -1, 1]).tolist()), "added_mass_matrix", "positive semi-definite"),
    (dict(added_mass_matrix=np.eye(6).tolist()), "added_mass_matrix", "not both"),
    (dict(added_mass_reference=[0.1, 0.0, 0.0]), "added_mass_reference", "added_mass_matrix"),
])
def test_bad_added_mass_is_refused_naming_the_field(fish, field, words):
    with pytest.raises(SceneError) as e:
        load_scene(_scene_with_fish(**fish))
    assert field in str(e.value) and words in str(e.value)


@pytest.mark.parametrize("force", [(0.0, 0.0, -120.0), (80.0, -30.0, 50.0)])
def test_external_force_reaches_the_vessel_in_the_statics(force):
    """``external_force`` (thrusters holding station, global axes, at the centre of gravity): a fish on a single
    cable at rest in still water — the cable's static pull on the vessel is the wet weight of cable and fish plus
    the thrust, whatever the cable's inclination (no drag at rest): to 1e-6 of the weight (statics tolerance)."""
    line = dict(name="cable", length=50.0, segments=10, diameter=0.0173, mass_per_length=1.04, EA=9.87e6,
                top="vessel", bottom={"body": "fish"})
    fish = dict(name="fish", kind="fish", mass=41.2, volume=0.035, inertia=[0.2, 4.0, 4.0], cg=[-0.1, 0.0, -0.2],
                cb=[-0.1, 0.0, -0.1], added_mass=[3.0, 35.0, 35.0], reference_area=0.03, reference_length=1.2,
                coefficients=dict(incidence_deg=[0, 10, 20, 90], drag=[0.3, 0.35, 0.45, 1.2],
                                  lift=[0.0, 0.0, 0.0, 0.0], moment=[0.0, 0.05, 0.1, 0.1]),
                external_force=list(force))
    sc = dict(name="thrust", water=dict(density=1025.0, gravity=9.81), vessel=dict(speed=0.0), lines=[line],
              bodies=[fish], solver=dict(dt=0.02))
    sim = _simulator(sc)
    w_cable = (1.04 - 1025.0 * np.pi * 0.0173 ** 2 / 4) * 9.81 * 50.0
    w_fish = (41.2 - 1025.0 * 0.035) * 9.81
    expected = np.array(force) + np.array([0.0, 0.0, -(w_cable + w_fish)])
    np.testing.assert_allclose(sim.top_force, expected, atol=1e-6 * (w_cable + w_fish))
