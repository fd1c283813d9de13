"""The numba kernels against their plain-numpy twins (towenv.verification.twin), and the tension-solver checks of
verification.md V9.

* every kernel equals its twin on random states (positions/velocities perturbing a built system, with a
  depth-dependent current) to ~1e-12 relative;
* ``tree_ldlt_solve`` equals a dense solve on a 40-segment uniform chain with s = 2(l/(c_L Δt))² = 200, a
  two-part tow (junction), a parallel tow (3 secondaries on one primary, two of them at one junction) and
  a series tow (aft tow point, drogue ball), each tree at s = 200 and at Δt = 0.02 s, and also with
  non-symmetric body blocks (the kernel's LU path);
* the thesis's shooting recursion (4.38)–(4.40) fails on that chain (relative error > 1e60), a regression
  that documents why it is not used (model.md 5.6);
* the row-scaled Jacobian J = −K is symmetric to round-off and negative definite on those trees;
* one full ``houbolt_step`` equals ``houbolt_step_np`` to 1e-9 (towed two-part, parallel and series tows
  with excitation and a current profile; a step with slack segments; a failed step), and 50 chained
  steps stay within 1e-8.

Scenes are plain dicts (docs/scene-format.md), validated by towenv.scene.load_scene when it exists.
"""
from __future__ import annotations

import copy
import functools
import math
from unittest import mock

import numpy as np
import pytest

from towenv.core import kernels as K
from towenv.core import simulator as simmod
from towenv.verification import twin
from towenv.core.system import MAX_SEGS_PER_NODE, build_system

from twin_cases import (CURRENT, DEP_TAB, EXCITATION, FISH_HTAB, FISH_TAB, RAMP, RTOL, SCENES,  # noqa: F401
                        _cable, _depressor, _fish, _scene, _simulator, chain_scene, kernel_and_twin_step,
                        parallel_scene, series_scene, two_part_scene)


@functools.lru_cache(maxsize=None)
def _static(name):
    """(System, static positions) of a scene (cached; callers must not modify them)."""
    sim = _simulator(SCENES[name]())
    return sim.system, sim.static_positions.copy()


def _rel(a, b):
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    assert a.shape == b.shape
    if b.size == 0:
        return 0.0
    scale = max(np.max(np.abs(b)), 1e-300)
    return float(np.max(np.abs(a - b)) / scale)


def _random_state(sys, r0, rng, dr=0.5, dv=1.5):
    r = r0 + dr * rng.standard_normal(r0.shape)
    v = np.array([3.0, 0.0, 0.0]) + dv * rng.standard_normal(r0.shape)
    return r, v


# ----------------------------------------------------------------------------------------------
# kernel calls with freshly allocated outputs
# ----------------------------------------------------------------------------------------------
def _k_segment_loads(sys, r, v):
    ns = sys.n_segments
    out = (np.zeros((ns, 3)), np.zeros(ns), np.zeros((ns, 2, 3)), np.zeros((ns, 2, 3, 3)), np.zeros((ns, 3, 3)))
    K.segment_loads(r, v, sys.seg_lo, sys.seg_up, sys.l0, sys.diam, sys.mu, sys.cn, sys.ct, sys.can, sys.cat,
                    sys.rho, sys.g, sys.cur_z, sys.cur_v, *out)
    return out


def _k_node_assembly(sys, r, v, drag, bmat, madd):
    nn = sys.n_nodes
    out = (np.zeros((nn, 3, 3)), np.zeros((nn, 3, 3)), np.zeros((nn, 3)))
    K.node_assembly(r, v, sys.node_kind, sys.node_nseg, sys.node_segs, sys.node_sgn, sys.l0, sys.diam, sys.mu,
                    sys.rho, sys.g, drag, bmat, madd, sys.pb_mass, sys.pb_vol, sys.pb_cda, sys.pb_ca, sys.cur_z,
                    sys.cur_v, *out)
    return out


def _k_tension_blocks(sys, tang, qvec, tens):
    kd = np.zeros(sys.n_segments)
    kb = np.zeros((sys.n_nodes, MAX_SEGS_PER_NODE, MAX_SEGS_PER_NODE))
    K.assemble_tension_system(sys.node_kind, sys.node_nseg, sys.node_segs, sys.node_sgn, tang, qvec, sys.l0,
                              sys.ea, tens, kd, kb)
    return kd, kb


def _k_tree_solve(sys, kd, kb, rhs):
    x = np.zeros_like(rhs)
    kd, kb, rhs = kd.copy(), kb.copy(), rhs.copy()      # the solve overwrites them
    ok = K.tree_ldlt_solve(sys.order, sys.seg_up, sys.seg_uplocal, sys.node_kind, sys.node_nseg, sys.node_segs,
                           sys.pos, kd, kb, rhs, x)
    assert ok
    return x


def _qvec(sys, tang, minv, dt):
    """q_{a,k} = ½Δt² M̃_a⁻¹ t_{s_k} in the kernel's node-local layout (plain numpy)."""
    q = np.zeros((sys.n_nodes, MAX_SEGS_PER_NODE, 3))
    for a in range(sys.n_nodes):
        for k in range(sys.node_nseg[a]):
            q[a, k] = 0.5 * dt * dt * minv[a] @ tang[sys.node_segs[a, k]]
    return q


# ----------------------------------------------------------------------------------------------
# constants and small helpers
# ----------------------------------------------------------------------------------------------
def test_twin_constants_match_kernels():
    for name in ("OK", "FAIL_NEWTON", "FAIL_NAN", "FAIL_STRETCH", "FAIL_ANGLE", "FREE", "PRESCRIBED_TOP",
                 "PRESCRIBED_AFT"):
        assert getattr(twin, name) == getattr(K, name), name


def test_kinematics_and_current_match():
    rng = np.random.default_rng(1)
    cur_z = np.array(CURRENT["depths"])
    cur_v = np.array(CURRENT["velocities"])
    out = np.empty(3)
    for z in np.concatenate([[5.0, 0.0, -20.0, -60.0, -80.0], -70.0 * rng.random(20)]):
        K.current_at(z, cur_z, cur_v, out)
        assert np.allclose(out, twin.current_np(z, cur_z, cur_v), rtol=RTOL, atol=1e-15)
    lam = np.empty((3, 3))
    w = np.empty(3)
    acc = np.empty(3)
    for _ in range(20):
        ang = rng.uniform(-1.2, 1.2, 3) * np.array([1.0, 1.0, 2.5])
        dang, domega = rng.standard_normal(3), rng.standard_normal(3)
        K.rotation_matrix(*ang, lam)
        L = twin.rotation_matrix_np(*ang)
        assert np.allclose(lam, L, rtol=0, atol=1e-15)
        assert np.allclose(L @ L.T, np.eye(3), atol=1e-15)
        K.euler_rates_to_omega(ang, dang, w)
        assert np.allclose(w, twin.euler_rates_to_omega_np(ang, dang), rtol=RTOL, atol=1e-15)
        K.omega_dot_to_euler_acc(ang, dang, w, domega, acc)
        ref = twin.omega_dot_to_euler_acc_np(ang, dang, w, domega)
        assert _rel(acc, ref) < 1e-13


# ----------------------------------------------------------------------------------------------
# loads on random states
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(SCENES))
def test_segment_loads_and_node_assembly_match(name):
    sys, r0 = _static(name)
    rng = np.random.default_rng(2)
    for trial in range(5):
        r, v = _random_state(sys, r0, rng)
        if trial == 0:      # a segment at rest relative to the water: zero drag, the |v_n| → 0 branch
            for a in (sys.seg_lo[0], sys.seg_up[0]):
                v[a] = twin.current_np(r[a, 2], sys.cur_z, sys.cur_v)
        tang, stretched, drag, bmat, madd = _k_segment_loads(sys, r, v)
        seg = twin.segment_loads_np(sys, r, v)
        for got, ref in ((tang, seg.tang), (stretched, seg.stretched), (drag, seg.drag), (bmat, seg.bmat),
                         (madd, seg.madd)):
            assert ref.shape == got.shape
            assert _rel(got, ref) < RTOL
        # node assembly: each implementation from its own segment loads
        mk, bk, fk = _k_node_assembly(sys, r, v, drag, bmat, madd)
        mt, bt, ft = twin.node_assembly_np(sys, r, v, seg)
        assert _rel(mk, mt) < RTOL
        assert _rel(bk, bt) < RTOL
        assert _rel(fk, ft) < RTOL


@pytest.mark.parametrize("name", list(SCENES))
def test_body_loads_and_mass_blocks_match(name):
    sys, _ = _static(name)
    assert sys.n_rigid >= 1
    rng = np.random.default_rng(3)
    f, m, bd = np.empty(3), np.empty(3), np.empty(1)
    att, atr, arr = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    lam = np.empty((3, 3))
    for b in range(sys.n_rigid):
        K.body_mass_blocks(b, sys.bp, att, atr, arr)
        A_tt, A_tr, A_rr = twin.body_mass_blocks_np(sys, b)
        assert _rel(att, A_tt) < RTOL and _rel(atr, A_tr) < RTOL and _rel(arr, A_rr) < RTOL
        for trial in range(40):
            ang = rng.uniform(-0.6, 0.6, 3) * np.array([0.5, 1.0, 3.0])
            K.rotation_matrix(*ang, lam)
            cur = 0.3 * rng.standard_normal(3)
            w = 0.5 * rng.standard_normal(3)
            # incidences from small to beyond the tables' ends (held values), both signs
            speed = rng.uniform(0.5, 4.0)
            inc_v, inc_h = np.radians(rng.uniform(-50, 50, 2))
            v_rel = speed * np.array([math.cos(inc_v) * math.cos(inc_h), math.sin(inc_h), math.sin(inc_v)])
            if trial == 0:
                v_rel[:] = 0.0                  # no relative velocity at the centroid: statics and damping only
            vb = v_rel + lam @ cur - np.cross(w, sys.bp[b, 7:10])    # tow-point velocity giving that v_r
            K.body_loads(b, lam, vb, w, sys.bp, sys.btab_n, sys.btab, sys.rho, sys.g, cur, f, m, bd)
            ft, mt, bdt = twin.body_loads_np(sys, b, lam, vb, w, cur)
            assert _rel(f, ft) < RTOL
            assert _rel(m, mt) < RTOL
            assert abs(bd[0] - bdt) <= RTOL * max(abs(bdt), 1e-300)


# ----------------------------------------------------------------------------------------------
# the tension system
# ----------------------------------------------------------------------------------------------
def _dt_for_s(sys, s_target):
    """Δt giving s = 2(l/(c_L Δt))² = s_target for the longest cable segment."""
    i = int(np.argmax(sys.l0))
    return sys.l0[i] * math.sqrt(2.0 * sys.mu[i] / (sys.ea[i] * s_target))


def _random_minv(sys, r, v, dt, rng, symmetric=True):
    """M̃⁻¹ (N, 3, 3) of a random state: cable/point-body node masses with implicit drag, plus a random
    anisotropic SPD block (a condensed rigid body) at each rigid-body node and, unless ``symmetric``, a
    non-symmetric damping block there (like a body's lift derivative)."""
    seg = twin.segment_loads_np(sys, r, v)
    mnode, bnode, _ = twin.node_assembly_np(sys, r, v, seg)
    mt = mnode + 11.0 * dt / 12.0 * bnode
    for a in sys.body_node:
        Q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
        mt[a] += Q @ np.diag(rng.uniform(50.0, 500.0, 3)) @ Q.T
        if not symmetric:
            D = rng.uniform(-100.0, 100.0, (3, 3)) / max(dt, 1e-3)
            mt[a] += 11.0 * dt / 12.0 * (D - D.T)
    minv = np.zeros_like(mt)
    free = sys.node_kind == twin.FREE
    minv[free] = np.linalg.inv(mt[free])
    return seg.tang, minv


def _chain_system(n=40, s=200.0):
    """A straight vertical uniform chain of n segments and its node inverse masses with s = 200."""
    sys = build_system(chain_scene(n))
    r = np.zeros((sys.n_nodes, 3))
    r[sys.lines[0].nodes, 2] = -np.arange(n + 1, dtype=float)
    l, mu, ea = sys.l0[0], sys.mu[0], sys.ea[0]
    dt = l * math.sqrt(2.0 * mu / (ea * s))
    assert abs(2.0 * (l / (math.sqrt(ea / mu) * dt)) ** 2 - s) < 1e-9 * s
    seg = twin.segment_loads_np(sys, r, np.zeros_like(r))
    minv = np.zeros((sys.n_nodes, 3, 3))
    minv[sys.node_kind == twin.FREE] = np.eye(3) / (mu * l)
    return sys, seg.tang, minv, dt


def _tree_cases():
    """(label, System, tangents, M̃⁻¹, Δt) for the chain and the three trees, each tree at s = 200 and at
    a physical Δt = 0.02 s (s ≪ 1)."""
    cases = [("chain40_s200",) + _chain_system()]
    rng = np.random.default_rng(4)
    for name in SCENES:
        sys, r0 = _static(name)
        for label, dt in (("s200", _dt_for_s(sys, 200.0)), ("dt0.02", 0.02)):
            r, v = _random_state(sys, r0, rng, dr=0.3, dv=1.0)
            tang, minv = _random_minv(sys, r, v, dt, rng)
            cases.append((f"{name}_{label}", sys, tang, minv, dt))
    return cases


def _nonsymmetric_cases():
    """The trees at Δt = 0.02 s with a non-symmetric block at every rigid-body node (LU path of the solve)."""
    cases = []
    rng = np.random.default_rng(8)
    for name in SCENES:
        sys, r0 = _static(name)
        r, v = _random_state(sys, r0, rng, dr=0.3, dv=1.0)
        tang, minv = _random_minv(sys, r, v, 0.02, rng, symmetric=False)
        cases.append((f"{name}_nonsym", sys, tang, minv, 0.02))
    return cases


TREE_CASES = _tree_cases()
TREE_IDS = [c[0] for c in TREE_CASES]
ALL_CASES = TREE_CASES + _nonsymmetric_cases()
ALL_IDS = [c[0] for c in ALL_CASES]


@pytest.mark.parametrize("case", ALL_CASES, ids=ALL_IDS)
def test_tension_matrix_matches_sparse_twin(case):
    _, sys, tang, minv, dt = case
    rng = np.random.default_rng(5)
    tens = rng.uniform(0.0, 3000.0, sys.n_segments)
    kd, kb = _k_tension_blocks(sys, tang, _qvec(sys, tang, minv, dt), tens)
    Kk = twin.blocks_to_sparse(sys, kd, kb).toarray()
    Kt = twin.tension_matrix_np(sys, tang, minv, dt).toarray()
    assert _rel(Kk, Kt) < RTOL
    # the kernel keeps exactly the tree pattern: nonzeros only between segments sharing a FREE node
    assert np.array_equal(Kk != 0.0, Kt != 0.0)
    rhs = rng.standard_normal(sys.n_segments)
    x_tree = _k_tree_solve(sys, kd, kb, rhs)
    x_lu = twin.solve_tension_np(twin.tension_matrix_np(sys, tang, minv, dt), rhs)
    assert _rel(x_tree, x_lu) < RTOL


@pytest.mark.parametrize("case", ALL_CASES, ids=ALL_IDS)
def test_tree_ldlt_solve_matches_dense_solve(case):
    _, sys, tang, minv, dt = case
    kd, kb = _k_tension_blocks(sys, tang, _qvec(sys, tang, minv, dt), np.zeros(sys.n_segments))
    Kd = twin.blocks_to_sparse(sys, kd, kb).toarray()
    rng = np.random.default_rng(6)
    for _ in range(3):
        rhs = rng.standard_normal(sys.n_segments)
        x_ref = np.linalg.solve(Kd, rhs)
        x = _k_tree_solve(sys, kd, kb, rhs)
        assert _rel(x, x_ref) < RTOL


@pytest.mark.parametrize("case", TREE_CASES, ids=TREE_IDS)
def test_row_scaled_jacobian_symmetric_negative_definite(case):
    """J = −K of the unsquared (row-scaled) constraints, rows formed with the coefficient tangents."""
    _, sys, tang, minv, dt = case
    kd, kb = _k_tension_blocks(sys, tang, _qvec(sys, tang, minv, dt), np.zeros(sys.n_segments))
    J = -twin.blocks_to_sparse(sys, kd, kb).toarray()
    assert np.max(np.abs(J - J.T)) <= 1e-14 * np.max(np.abs(J))
    assert np.max(np.linalg.eigvalsh(0.5 * (J + J.T))) < 0.0


def test_chain_is_the_uniform_s200_matrix():
    """The 40-segment chain matrix, normalised by ½Δt²/m, is tridiag(−1, 2 + s, −1) (top row 1 + s)."""
    sys, tang, minv, dt = _chain_system()
    m = sys.mu[0] * sys.l0[0]
    Kn = twin.tension_matrix_np(sys, tang, minv, dt).toarray() / (0.5 * dt * dt / m)
    seg = sys.lines[0].segments                  # top → bottom
    Kn = Kn[np.ix_(seg, seg)]
    ref = np.diag(np.full(40, 202.0)) - np.eye(40, k=1) - np.eye(40, k=-1)
    ref[0, 0] = 201.0
    assert np.allclose(Kn, ref, rtol=1e-12, atol=1e-12)


def test_thesis_recursion_fails_on_s200_chain_while_tree_solve_is_accurate():
    """Regression (verification.md V9, model.md 5.6): the printed shooting recursion (4.38)–(4.40) amplifies
    round-off like λ^n (λ ≈ s for large s); on 40 segments at s = 200 its relative error exceeds 1e60."""
    sys, tang, minv, dt = _chain_system()
    kd, kb = _k_tension_blocks(sys, tang, _qvec(sys, tang, minv, dt), np.zeros(sys.n_segments))
    Kd = twin.blocks_to_sparse(sys, kd, kb).toarray()
    seg = sys.lines[0].segments[::-1]            # thesis numbering: bottom → top
    Kc = Kd[np.ix_(seg, seg)]
    # J δT = −g with J = −K:  E_i δT_{i−1} − F_i δT_i + G_i δT_{i+1} = −g_i
    E = np.concatenate([[0.0], -np.diag(Kc, -1)])
    F = np.diag(Kc).copy()
    G = np.concatenate([-np.diag(Kc, 1), [0.0]])
    rng = np.random.default_rng(7)
    g = rng.standard_normal(40)
    x_ref = np.linalg.solve(Kc, g)
    x_tree = _k_tree_solve(sys, kd, kb, g[np.argsort(seg)])[seg]
    with np.errstate(all="ignore"):
        x_rec = twin.thesis_shooting_recursion(E, F, G, -g)
    err_rec = np.linalg.norm(x_rec - x_ref) / np.linalg.norm(x_ref)
    err_tree = np.linalg.norm(x_tree - x_ref) / np.linalg.norm(x_ref)
    assert err_tree < 1e-12
    assert not np.isfinite(err_rec) or err_rec > 1e60
    # ... whereas on a short chain at small s the same recursion is fine (it is implemented correctly)
    n = 8
    Kc8 = np.diag(np.full(n, 2.5)) - np.eye(n, k=1) - np.eye(n, k=-1)
    g8 = rng.standard_normal(n)
    x8 = twin.thesis_shooting_recursion(np.r_[0.0, np.ones(n - 1)], np.diag(Kc8), np.r_[np.ones(n - 1), 0.0], -g8)
    assert np.allclose(x8, np.linalg.solve(Kc8, g8), rtol=1e-10, atol=1e-12)


# ----------------------------------------------------------------------------------------------
# one full Houbolt step, and 50 chained steps
# ----------------------------------------------------------------------------------------------
def _dynamic_sim(name, seconds=2.0):
    """A Simulator of the scene, towed with heave/surge excitation, advanced ``seconds`` by the kernels."""
    sim = _simulator(SCENES[name](excitation=EXCITATION))
    sim.advance(seconds)
    return sim


def _kernel_step(sim, dt, top):
    st, it, el, md = K.houbolt_step_entry(dt, top, *sim._args, sim.settings.array(), sim._state, sim._ws, sim.comp)
    return st, it


def _top(sim, k=1):
    return sim.path.position(np.array([sim.t + k * sim.dt]))[0]


def _assert_same_state(twin_state, sim, rtol):
    assert _rel(twin_state.hist_r, sim.hist_r) < rtol
    assert _rel(twin_state.tens_hist, sim.tens_hist) < rtol
    assert _rel(twin_state.hist_ang, sim.hist_ang) < rtol
    assert _rel(twin_state.top_react, sim.top_react) < rtol


@pytest.mark.parametrize("name", list(SCENES))
def test_houbolt_step_matches_twin(name):
    sim = _dynamic_sim(name)
    dt = sim.dt
    top = _top(sim)
    before = sim.snapshot()
    trace = []
    res = twin.houbolt_step_np(sim, dt, top, trace=trace)
    # the twin does not touch the simulator
    for field in ("hist_r", "hist_ang", "tens_hist", "top_react"):
        assert np.array_equal(getattr(sim, field), getattr(before, field)), field
    st, it = _kernel_step(sim, dt, top)
    assert st == K.OK and res.status == twin.OK
    assert it == res.iterations == len(trace)
    _assert_same_state(res, sim, 1e-9)
    # every iterate's tension matrix K = −J: its symmetric part is positive definite (K itself is
    # non-symmetric only through a rigid body's hydrodynamic damping in its node's M̃)
    for rec in trace:
        Kt = rec["K"].toarray()
        assert np.min(np.linalg.eigvalsh(0.5 * (Kt + Kt.T))) > 0.0


@pytest.mark.parametrize("name", ["two_part", "series", "kirchhoff", "splice"])
def test_fifty_houbolt_steps_match_twin(name):
    sim = _dynamic_sim(name)
    dt = sim.dt
    state = sim
    worst = 0.0
    for k in range(50):
        top = _top(sim)
        state = twin.houbolt_step_np(state, dt, top)
        st, it = _kernel_step(sim, dt, top)
        sim.step_count += 1
        assert st == K.OK and state.status == twin.OK, k
        assert it == state.iterations, k
        worst = max(worst, _rel(state.hist_r[0], sim.hist_r[0]), _rel(state.tens_hist[0], sim.tens_hist[0]))
    assert worst < 1e-8
    _assert_same_state(state, sim, 1e-8)


def test_houbolt_step_with_slack_segments_matches_twin():
    """A hanging chain whose tow point drops 0.5 m in one step: the first Newton update clamps every
    tension at 0 and the slack rule (identity rows, T held at 0) is active in the next iterations."""
    sim = _simulator(chain_scene(20))
    sim.advance(0.2)
    top = _top(sim) - np.array([0.0, 0.0, 0.5])
    trace = []
    res = twin.houbolt_step_np(sim, sim.dt, top, trace=trace)
    st, it = _kernel_step(sim, sim.dt, top)
    assert st == K.OK and res.status == twin.OK and it == res.iterations
    assert np.all(trace[0]["tens"] == 0.0)
    assert any(np.any(rec["tens"] == 0.0) for rec in trace[1:])
    _assert_same_state(res, sim, 1e-9)


def test_failed_houbolt_step_matches_twin_and_leaves_state():
    """With too few iterations both report FAIL_NEWTON after the same iterations and keep the old state."""
    sim = _dynamic_sim("two_part")
    dt = sim.dt
    for _ in range(100):                # a step that needs two iterations or more (the adaptive predictor's
        top = _top(sim)                 # start often converges in one)
        probe = twin.houbolt_step_np(sim, dt, top)
        if probe.iterations >= 2:
            break
        sim.advance_steps(1)
    assert probe.status == twin.OK and probe.iterations >= 2
    settings = sim.settings.array()
    settings[2] = probe.iterations - 1
    like = twin.TwinStep(sim.system, settings, sim.hist_r, sim.hist_ang, sim.tens_hist, sim.top_react,
                         body_chart=sim.body_chart, older=sim.older)
    res = twin.houbolt_step_np(like, dt, top)
    before = sim.snapshot()
    st, it, el, md = K.houbolt_step_entry(dt, top, *sim._args, settings, sim._state, sim._ws, sim.comp)
    assert st == res.status == K.FAIL_NEWTON
    assert it == res.iterations == probe.iterations - 1
    assert el == res.element
    assert abs(md - res.max_dT) <= 1e-6 * md
    for field in ("hist_r", "hist_ang", "tens_hist", "top_react"):
        assert np.array_equal(getattr(sim, field), getattr(before, field))
        assert np.array_equal(getattr(res, field), getattr(before, field))
