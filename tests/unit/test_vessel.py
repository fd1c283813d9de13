"""Tests of towenv.vessel: particulars, closed-form RAOs, RAO tables, motion records
and the tow-point oscillation (``shared/reference/sea-and-vessel.md`` sections 0, 3-5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from towenv import stats
from towenv.core.excitation import TowPointPath
from towenv.sea import G, SeaState, synthesize
from towenv.vessel import (
    DOFS,
    VESSELS,
    ClosedFormRAO,
    MotionRecord,
    RAOTable,
    TowPointMotion,
    VesselParticulars,
    jmo_heave_pitch,
    lever_arm_matrix,
    response_moments,
)

COASTAL = VESSELS["coastal_survey"]


@pytest.fixture(scope="module")
def sea_head():
    return SeaState(hs=0.88, tp=4.7, heading_deg=180.0)


@pytest.fixture(scope="module")
def record_head(sea_head):
    return synthesize(sea_head, duration=3600.0, seed=7)


# --------------------------------------------------------------------------
# particulars
# --------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, name", [
    (dict(length=-15.0), "length"),
    (dict(block_coefficient=0.3), "block_coefficient"),
    (dict(block_coefficient=0.95), "block_coefficient"),
    (dict(beam=20.0), "beam"),
    (dict(draft=5.0), "draft"),
    (dict(roll_damping_ratio=0.0), "roll_damping_ratio"),
    (dict(gm=-1.0), "gm"),
    (dict(roll_period=100.0), "roll_period"),
    (dict(displacement=500.0), "displacement"),
    (dict(tow_point=(1.0, 2.0)), "tow_point"),
])
def test_particulars_validation(kwargs, name):
    base = dict(length=15.0, beam=4.5, draft=1.2, block_coefficient=0.45)
    base.update(kwargs)
    with pytest.raises(ValueError, match=name):
        VesselParticulars(**base)


def test_particulars_error_states_range():
    with pytest.raises(ValueError, match=r"\[0\.35, 0\.9\]"):
        VesselParticulars(15.0, 4.5, 1.2, 0.2)


def test_presets():
    c, r = VESSELS["coastal_survey"], VESSELS["research_vessel"]
    assert 10.0 <= c.length <= 20.0 and 60.0 <= r.length <= 80.0
    assert c.displacement == pytest.approx(1.025 * 0.45 * 15 * 4.5 * 1.2)
    assert c.heave_pitch_natural_period == pytest.approx(2 * math.pi / math.sqrt(G / 2.4))
    assert 3.5 < c.roll_natural_period < 5.0 and 8.0 < r.roll_natural_period < 12.0
    assert c.description and r.description
    assert VESSELS["coastal_survey"].with_(gm=0.8).roll_natural_period > c.roll_natural_period


# --------------------------------------------------------------------------
# closed-form RAOs
# --------------------------------------------------------------------------
@pytest.mark.parametrize("beta_deg, speed", [(180, 0.0), (180, 3.0), (135, 3.0), (90, 0.0), (0, 0.0), (30, 1.0)])
def test_long_wave_limit(beta_deg, speed):
    """lambda >> L: heave -> 1, pitch -> i k cos(beta) (the wave slope), roll -> -i k sin(beta)."""
    w = 0.08
    k = w * w / G
    b = math.radians(beta_deg)
    H = ClosedFormRAO(COASTAL)(w, b, speed)
    assert abs(H[2] - 1.0) < 2e-3
    assert abs(H[4] - 1j * k * math.cos(b)) < 5e-3 * k
    assert abs(H[3] - (-1j * k * math.sin(b))) < 2e-2 * k     # damping term ~ 2 zeta w_e/w4
    assert abs(H[0] - (-1j * math.cos(b))) < 5e-3      # surface particle displacement
    assert abs(H[1] - (-1j * math.sin(b))) < 5e-3
    assert H[5] == 0


@pytest.mark.parametrize("beta_deg", [180, 135, 90, 45, 0])
def test_short_wave_limit(beta_deg):
    w = np.array([6.0, 8.0, 12.0])   # lambda = 1.7, 0.96, 0.43 m << L = 15 m
    H = ClosedFormRAO(COASTAL)(w, math.radians(beta_deg), 2.0)
    assert np.all(np.abs(H[:, 2]) < 0.01)
    assert np.all(np.abs(H[:, 4]) < 0.01 * w**2 / G)      # pitch << wave slope
    assert np.all(np.abs(H[-1]) < 1e-4)


def test_jmo_matches_reference_table():
    """JMO column of the capytaine comparison (reference section 4, caveat 4): 15 m box, Cb = 1, U = 0."""
    w = np.array([0.6, 1.0, 1.2, 1.5, 1.8, 2.0, 2.6])
    H3, H5, _ = jmo_heave_pitch(w, math.pi, 0.0, 15.0, 4.5, 1.2, 1.0)
    np.testing.assert_allclose(np.abs(H3), [0.99, 0.91, 0.81, 0.56, 0.23, 0.02, 0.03], atol=0.006)
    np.testing.assert_allclose(np.degrees(np.abs(H5)), [2.1, 5.5, 7.4, 9.4, 8.9, 6.6, 0.5], atol=0.06)
    H3b, _, _ = jmo_heave_pitch(w, math.pi / 2, 0.0, 15.0, 4.5, 1.2, 1.0)
    np.testing.assert_allclose(np.abs(H3b), [1.00, 1.00, 1.00, 0.98, 0.93, 0.86, 0.19], atol=0.006)


@pytest.mark.parametrize("L, B, T, Cb, hs, tp, head, expect", [
    (15, 4.5, 1.2, 0.45, 0.88, 4.7, 180, (0.40, 0.76, 0.75)),
    (15, 4.5, 1.2, 0.45, 0.88, 7.5, 180, (0.48, 0.69, 0.55)),
    (15, 4.5, 1.2, 0.45, 0.88, 4.7, 0, (0.19, 0.36, 0.14)),
    (40, 10, 3, 0.55, 1.88, 6.8, 180, (0.62, 1.48, 0.89)),
])
def test_reference_example_outputs(L, B, T, Cb, hs, tp, head, expect):
    """Section 5 table: CG heave sig. ampl., stern tow-point heave sig. ampl., tow-point vertical velocity rms."""
    sea = SeaState(hs=hs, tp=tp, heading_deg=head)
    r = response_moments(sea, VesselParticulars(L, B, T, Cb), lever_arm=(-L / 2, 0, 0), speed=3.0,
                         omega_range=(0.3 * sea.omega_p, 5 * sea.omega_p))
    got = (2 * math.sqrt(r["ship"][0, 2]), 2 * math.sqrt(r["tow_point"][0, 2]), math.sqrt(r["tow_point"][1, 2]))
    np.testing.assert_allclose(got, expect, rtol=0.02, atol=0.006)


def test_roll_resonance_and_symmetry():
    rao = ClosedFormRAO(COASTAL)
    w4 = 2 * math.pi / COASTAL.roll_natural_period
    k = w4 * w4 / G
    H = rao(w4, math.pi / 2, 0.0)
    mu = math.exp(-k * COASTAL.draft) * 3 * (math.sin(s := k * COASTAL.beam / 2) - s * math.cos(s)) / s**3
    assert abs(H[3]) == pytest.approx(k * mu / (2 * COASTAL.roll_damping_ratio), rel=1e-9)
    # port/starboard mirror: sway, roll, yaw antisymmetric; the rest symmetric
    Hp, Hm = rao(1.1, math.radians(60), 2.0), rao(1.1, math.radians(-60), 2.0)
    sign = np.array([1, -1, 1, -1, 1, -1])
    np.testing.assert_allclose(Hm, sign * Hp, atol=1e-14)
    assert np.all(np.abs(rao(np.array([0.5, 1.5, 3.0]), math.pi, 3.0)[:, 3]) < 1e-15)


def test_calibration_and_no_horizontal():
    base = ClosedFormRAO(COASTAL)(1.2, 2.5, 2.0)
    cal = ClosedFormRAO(COASTAL, calibration={"pitch": 1.5}, horizontal="none")(1.2, 2.5, 2.0)
    assert cal[4] == pytest.approx(1.5 * base[4])
    assert cal[0] == 0 and cal[1] == 0 and cal[2] == base[2]
    with pytest.raises(ValueError, match="calibration key 'heav'"):
        ClosedFormRAO(COASTAL, calibration={"heav": 1.0})


# --------------------------------------------------------------------------
# RAO table
# --------------------------------------------------------------------------
def test_rao_table_roundtrip(tmp_path):
    rao = ClosedFormRAO(COASTAL)
    w = np.linspace(0.2, 4.0, 77)
    heads = np.arange(0.0, 181.0, 5.0)    # resonances move with heading at speed: tabulate densely
    table = RAOTable.from_rao(rao, w, heads, speed=2.0)
    path = table.to_csv(tmp_path / "rao.csv")
    back = RAOTable.from_csv(path)
    assert back.symmetric and back.omega.size == 77 and back.headings_deg.size == heads.size
    # grid points reproduce the model
    W, B = np.meshgrid(w, np.radians(heads))
    np.testing.assert_allclose(back(W, B), rao(W, B, 2.0), atol=1e-9)
    # starboard headings come from the mirror (sway/roll/yaw change sign)
    np.testing.assert_allclose(back(w, math.radians(225.0)), rao(w, math.radians(225.0), 2.0), atol=1e-9)
    np.testing.assert_allclose(back(w, math.radians(-45.0)), rao(w, math.radians(-45.0), 2.0), atol=1e-9)
    # in-between frequencies and headings: interpolation error small against the peak values
    wf = np.linspace(0.25, 3.9, 300)
    for hd in (97.5, 172.5, 201.0):
        Ht, Hm = back(wf, math.radians(hd)), rao(wf, math.radians(hd), 2.0)
        scale = np.abs(rao(w[:, None], np.radians(heads)[None, :], 2.0)).max(axis=(0, 1))
        assert np.all(np.abs(Ht - Hm).max(axis=0) <= 0.06 * scale + 1e-12)
    # above the table: zero (default) or held
    assert np.all(back(5.0, math.pi) == 0)
    held = RAOTable.from_csv(path, above="hold")
    np.testing.assert_allclose(held(5.0, math.pi), back(w[-1], math.pi), atol=1e-12)


def test_rao_table_units_and_single_heading(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("omega,heave_amp,heave_phase_deg,pitch_amp,pitch_phase_deg\n"
                 "0.5,1.0,0,2.0,-90\n1.0,0.8,-10,5.0,-100\n2.0,0.1,-80,1.0,-170\n")
    tab = RAOTable.from_csv(p)
    H = tab(np.array([0.5, 1.0, 0.75]), np.array([0.0, 2.0, 3.0]))
    assert H[0, 4] == pytest.approx(math.radians(2.0) * np.exp(-0.5j * math.pi))   # deg/m -> rad/m
    assert H[1, 2] == pytest.approx(0.8 * np.exp(-1j * math.radians(10)))
    assert H[2, 2] == pytest.approx(0.5 * (1.0 + 0.8 * np.exp(-1j * math.radians(10))))   # complex linear
    assert np.all(H[:, [0, 1, 3, 5]] == 0)
    lag = RAOTable.from_csv(p, phase_convention="lag", rotation_unit="rad")
    assert lag(1.0, 0.0)[4] == pytest.approx(5.0 * np.exp(1j * math.radians(100)))


@pytest.mark.parametrize("text, msg", [
    ("omega,heave_amp\n1,1\n", "'heave_phase_deg' is missing"),
    ("omega,heave_phase_deg\n1,1\n", "'heave_amp' is missing"),
    ("w,heave_amp,heave_phase_deg\n1,1,0\n", "unknown column 'w'"),
    ("heave_amp,heave_phase_deg\n1,0\n", "missing required column 'omega'"),
    ("omega,heave_amplitude,heave_phase_deg\n1,1,0\n", "unknown column 'heave_amplitude'"),
    ("omega,heading_deg\n1,0\n", "no DOF columns"),
    ("omega,heave_amp,heave_phase_deg\n1,x,0\n", "column 'heave_amp': not a number"),
    ("omega,heave_amp,heave_phase_deg\n1,-1,0\n", "'heave_amp' has negative"),
    ("omega,heave_amp,heave_phase_deg\n1,1,0\n1,1,0\n", "repeated values"),
    ("heading_deg,omega,heave_amp,heave_phase_deg\n0,1,1,0\n90,1.5,1,0\n", "same frequencies"),
])
def test_rao_table_header_errors(tmp_path, text, msg):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(ValueError, match=msg):
        RAOTable.from_csv(p)


def test_rao_table_encounter_mode():
    w = np.linspace(0.2, 5.0, 200)
    zero = RAOTable.from_rao(ClosedFormRAO(COASTAL), w, np.arange(0, 181, 10.0), speed=0.0, frequency="encounter")
    U, wq = 3.0, np.array([1.0, 2.5])          # following seas: w_e = 0.69 and -1.32 rad/s
    we = wq - wq**2 / G * U
    H = zero(wq, 0.0, U)
    np.testing.assert_allclose(H[0], zero(we[0], 0.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(H[1], np.conj(zero(-we[1], math.pi, 0.0)), atol=1e-12)


# --------------------------------------------------------------------------
# motion record, lever arm, heading rotation
# --------------------------------------------------------------------------
def _write_record(path, t, **cols):
    names = ["t"] + list(cols)
    with open(path, "w") as fh:
        fh.write(",".join(names) + "\n")
        for i in range(len(t)):
            fh.write(",".join(repr(float(v)) for v in [t[i]] + [cols[c][i] for c in cols]) + "\n")


def test_lever_arm_pure_pitch(tmp_path):
    t = np.arange(0.0, 60.0, 0.05)
    pitch_deg = 3.0 * np.sin(2 * math.pi * t / 6.0)
    _write_record(tmp_path / "m.csv", t, pitch=pitch_deg)
    rec = MotionRecord.from_csv(tmp_path / "m.csv")
    lever = (-7.5, 0.0, 0.0)
    tpm = TowPointMotion(rec, None, lever)
    tq = np.linspace(1.0, 50.0, 500)
    x = tpm.offset(tq)
    pitch = np.radians(3.0 * np.sin(2 * math.pi * tq / 6.0))
    np.testing.assert_allclose(x[:, 2], -lever[0] * pitch, atol=2e-6)      # z = -x_p * pitch (bow down +)
    assert np.all(np.abs(x[:, :2]) < 1e-12)
    # an A-frame height turns pitch into surge: surge_P = z_p * pitch
    x2 = TowPointMotion(rec, None, (-7.5, 0.0, 3.0)).offset(tq)
    np.testing.assert_allclose(x2[:, 0], 3.0 * pitch, atol=1e-6)
    # the matrix itself (Faltinsen eq. 3.9)
    Tm = lever_arm_matrix((2.0, 3.0, 4.0))
    eta = np.eye(6)
    np.testing.assert_allclose(Tm @ eta[4], [4.0, 0.0, -2.0])
    np.testing.assert_allclose(Tm @ eta[3], [0.0, -4.0, 3.0])
    np.testing.assert_allclose(Tm @ eta[5], [-3.0, 2.0, 0.0])


def test_heading_rotation_and_record_kinematics(tmp_path):
    t = np.arange(0.0, 40.0, 0.02)
    surge = 0.5 * np.sin(1.3 * t)
    _write_record(tmp_path / "s.csv", t, surge=surge)
    rec = MotionRecord.from_csv(tmp_path / "s.csv", remove_mean=False)
    tq = np.linspace(2.0, 30.0, 300)
    x90 = TowPointMotion(rec, None, (0, 0, 0), heading=math.pi / 2).offset(tq)
    np.testing.assert_allclose(x90[:, 1], 0.5 * np.sin(1.3 * tq), atol=1e-6)      # surge -> global +y
    assert np.all(np.abs(x90[:, [0, 2]]) < 1e-12)
    # time-varying heading: velocity/acceleration consistent with the offset
    tpm = TowPointMotion(rec, None, (-5.0, 1.0, 2.0), heading_of=lambda tt: 0.1 * tt)
    tf = np.arange(5.0, 6.0, 1e-3)
    x, v, a = tpm.kinematics(tf)
    np.testing.assert_allclose(v[2:-2], np.gradient(x, tf, axis=0)[2:-2], atol=2e-5)
    np.testing.assert_allclose(a[2:-2], np.gradient(v, tf, axis=0)[2:-2], atol=2e-4)
    # FSD axes: sway/heave/pitch/yaw negated
    _write_record(tmp_path / "f.csv", t, heave=surge, roll=surge)
    fsd = MotionRecord.from_csv(tmp_path / "f.csv", axes="fsd", remove_mean=False).motion(tq)
    np.testing.assert_allclose(fsd[:, 2], -0.5 * np.sin(1.3 * tq), atol=1e-6)
    np.testing.assert_allclose(fsd[:, 3], np.radians(0.5 * np.sin(1.3 * tq)), atol=1e-6)
    with pytest.raises(ValueError, match="record times"):
        rec.motion([100.0])
    bad = tmp_path / "b.csv"
    bad.write_text("time,heave\n0,1\n1,2\n")
    with pytest.raises(ValueError, match="unknown column 'time'"):
        MotionRecord.from_csv(bad)


# --------------------------------------------------------------------------
# tow-point motion from a wave record
# --------------------------------------------------------------------------
def test_linear_superposition_spectrum(sea_head, record_head):
    """Tow-point heave PSD (Welch) = |H_tp|^2 S in the encounter domain (head seas, 3 m/s)."""
    U = 3.0
    tpm = TowPointMotion("coastal_survey", record_head, speed=U, heading=0.0)
    dt = 0.1
    z = tpm.offset(np.arange(0.0, 3600.0, dt))[:, 2]
    we_w, P = stats.welch_psd(z, dt, nperseg=1024)
    w = np.linspace(0.3 * sea_head.omega_p, 5 * sea_head.omega_p, 20000)
    Htp = tpm.transfer(w, math.pi, U)[:, 2]
    np.testing.assert_allclose(Htp, ClosedFormRAO(COASTAL)(w, math.pi, U)[:, 2] + 7.5 * ClosedFormRAO(COASTAL)(
        w, math.pi, U)[:, 4])
    we = w + w * w / G * U
    Se = np.abs(Htp) ** 2 * sea_head.density(w) / (1 + 2 * w * U / G)      # S(w_e) = |H|^2 S(w) / |dw_e/dw|
    Sa = np.interp(we_w, we, Se, left=0.0, right=0.0)
    m0 = np.trapezoid(Se, we)
    assert np.var(z) == pytest.approx(m0, rel=0.03)
    for lo, hi in [(0.8, 1.4), (1.4, 1.8), (1.8, 2.2), (2.2, 2.8), (2.8, 4.0)]:
        m = (we_w >= lo) & (we_w < hi)
        assert P[m].sum() == pytest.approx(Sa[m].sum(), rel=0.2)
    assert np.abs(P - Sa).max() < 0.35 * Sa.max()


def test_determinism(sea_head):
    t = np.arange(0.0, 200.0, 0.5)
    path = TowPointPath(dict(speed=2.0, manoeuvres=[dict(type="turn", start_time=50, radius=40, angle_deg=90)]))
    a = TowPointMotion.from_path(path, "coastal_survey", synthesize(sea_head, 600.0, seed=11)).offset(t)
    b = TowPointMotion.from_path(path, "coastal_survey", synthesize(sea_head, 600.0, seed=11)).offset(t)
    c = TowPointMotion.from_path(path, "coastal_survey", synthesize(sea_head, 600.0, seed=12)).offset(t)
    assert np.array_equal(a, b)
    assert not np.allclose(a, c)
    # chunking / call pattern does not matter
    tpm = TowPointMotion.from_path(path, "coastal_survey", synthesize(sea_head, 600.0, seed=11))
    step = np.concatenate([tpm.offset(t[i:i + 7]) for i in range(0, t.size, 7)])
    np.testing.assert_allclose(step, a, rtol=0, atol=1e-12)


def test_continuity_across_speed_and_heading_change(sea_head):
    rec = synthesize(SeaState(0.88, 4.7, heading_deg=150.0), 600.0, seed=3)
    path = TowPointPath(dict(speed=3.0, manoeuvres=[
        dict(type="speed_change", start_time=10.0, duration=2.0, final_speed=1.5),
        dict(type="turn", start_time=14.0, radius=25.0, angle_deg=90.0)]))
    tpm = TowPointMotion.from_path(path, "coastal_survey", rec)
    dt = 1e-3
    for t0 in (9.9, 11.9, 13.9):                 # start and end of the speed change, start of the turn
        t = np.arange(t0, t0 + 0.2, dt)
        x, v, a = tpm.kinematics(t)
        steps = np.abs(np.diff(x, axis=0))
        assert np.all(steps <= 1.02 * np.abs(v).max(axis=0) * dt + 1e-9)
        # velocity equals the derivative of the offset (kinks of the mean path only perturb +-h)
        far = np.abs(t - round(t0 + 0.1, 1)) > 0.01
        vn = np.gradient(x, t, axis=0)
        assert np.abs(v - vn)[far][1:-1].max() < 1e-3 * np.abs(v).max() + 1e-6
    # inside the turn: acceleration consistent too
    t = np.arange(20.0, 20.5, dt)
    x, v, a = tpm.kinematics(t)
    np.testing.assert_allclose(a[2:-2], np.gradient(v, t, axis=0)[2:-2], atol=1e-4 * np.abs(a).max())


def test_long_waves_tow_point_follows_surface():
    """lambda >> L: the tow point moves with the free surface at its own global position
    (checks heave/pitch/roll signs, lever arm, heading rotation and the wave-frame offset)."""
    sea = SeaState(0.5, 40.0, spectrum="bretschneider", heading_deg=120.0)
    rec = synthesize(sea, 600.0, seed=5, omega_range=(0.1, 0.2))
    psi0 = math.radians(20.0)
    path = TowPointPath(dict(speed=2.0, heading_deg=math.degrees(psi0),
                             manoeuvres=[dict(type="turn", start_time=100, radius=200, angle_deg=60)]))
    lever = (-7.5, 1.5, 0.0)
    tpm = TowPointMotion.from_path(path, ClosedFormRAO(COASTAL, horizontal="none"), rec, lever)
    t = np.arange(0.0, 300.0, 1.0)
    z = tpm.offset(t)[:, 2]
    pos = path.mean_path(t)[0]
    # the record's earth frame has x along the initial heading
    c, s = math.cos(psi0), math.sin(psi0)
    xe, ye = c * pos[:, 0] + s * pos[:, 1], -s * pos[:, 0] + c * pos[:, 1]
    eta = rec.elevation(t, xe, ye)
    assert np.abs(z - eta).max() < 0.02 * np.abs(eta).max()


def test_tow_point_path_integration(record_head):
    path = TowPointPath(dict(speed=2.0))
    tpm = TowPointMotion.from_path(path, "coastal_survey", record_head)
    path.oscillations.append(tpm)
    t = np.array([0.0, 30.0, 60.0])
    pos = path.position(t)
    mean = path.mean_path(t)[0]
    np.testing.assert_allclose(pos[0], mean[0])                       # ramp = 0 at t = 0
    np.testing.assert_allclose(pos[2] - mean[2], tpm.offset([60.0])[0])  # ramp finished
    assert tpm.lever_arm.tolist() == list(COASTAL.tow_point)


def test_argument_errors(record_head):
    with pytest.raises(ValueError, match="wave"):
        TowPointMotion("coastal_survey", None)
    with pytest.raises(ValueError, match="lever_arm"):
        TowPointMotion("coastal_survey", record_head, (1.0, 2.0))
    with pytest.raises(ValueError, match="unknown vessel preset"):
        TowPointMotion("trawler", record_head)
    with pytest.raises(ValueError, match="track_point"):
        TowPointMotion("coastal_survey", record_head, track_point="stern")
    assert len(DOFS) == 6
