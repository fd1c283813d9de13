"""Junctions, series and parallel multi-tows, and the qualitative turn behaviour (verification.md V8)."""
import numpy as np
import pytest

import towenv
import towenv.core.kernels as K


def _steady(name):
    sc = towenv.load_scene(name).with_overrides(**{"vessel.excitation": [], "vessel.manoeuvres": []})
    return towenv.Simulator(sc)


def _node_residual(sim, node):
    """Σ σ T t + F_o − M r̈ at a node in steady tow (r̈ = 0): the node's equation of motion."""
    s = sim.system
    r = sim.positions
    v = np.tile(sim.path.initial_velocity(), (s.n_nodes, 1))
    tang, stretched, drag, bmat, madd, mnode, bnode, fnode = sim._ws[:8]
    K.segment_loads(r, v, s.seg_lo, s.seg_up, s.l0, s.diam, s.mu, s.cn, s.ct, s.can, s.cat, s.rho, s.g,
                    s.cur_z, s.cur_v, tang, stretched, drag, bmat, madd)
    K.node_assembly(r, v, s.node_kind, s.node_nseg, s.node_segs, s.node_sgn, s.l0, s.diam, s.mu, s.rho, s.g,
                    drag, bmat, madd, s.pb_mass, s.pb_vol, s.pb_cda, s.pb_ca, s.cur_z, s.cur_v, mnode, bnode, fnode)
    out = np.zeros(3)
    K.node_reaction(node, r, r, r, r, sim.dt, s.node_nseg, s.node_segs, s.node_sgn, tang, sim.tensions,
                    mnode, fnode, out)
    return out


@pytest.mark.parametrize("name", ["two_part_tow_1", "parallel_multitow"])
def test_junction_force_balance(name):
    """At every 3-segment junction the three tensions and the node's own loads balance in steady tow,
    to the Newton tolerance (0.5 N on ~kN tensions)."""
    sim = _steady(name)
    sim.advance(30.0)
    junctions = [a for a in range(sim.system.n_nodes)
                 if sim.system.node_nseg[a] >= 3 and sim.system.node_kind[a] == K.FREE]
    assert junctions, "scene has no junction"
    for a in junctions:
        res = _node_residual(sim, a)
        scale = max(sim.tensions[sim.system.node_segs[a, :sim.system.node_nseg[a]]])
        assert np.linalg.norm(res) < 1e-3 * scale + 0.5


@pytest.mark.parametrize("name", ["series_multitow", "parallel_multitow", "two_part_tow_1"])
def test_multitow_runs_and_settles_in_steady_tow(name):
    """Series (aft tow points) and parallel (three junctions) tows settle: after 40 s of steady tow every
    body moves with the ship (relative velocity < 1 cm/s) and the pitch rates have died out."""
    sim = _steady(name)
    sim.advance(40.0)
    u = sim.path.initial_velocity()
    for b in sim.system.bodies:
        st = sim.body_state(b.name)
        assert np.linalg.norm(st["velocity"] - u) < 0.01, b.name
        assert np.all(np.abs(st["omega"]) < 1e-3), b.name
        assert np.all(np.isfinite(st["position"]))


@pytest.mark.parametrize("name,inside_expected", [("two_part_turn", True), ("series_multitow", True),
                                                   ("parallel_multitow", False)])
def test_turn_bodies_track_inside_and_deepen(name, inside_expected):
    """V8 (thesis §4.4, L3944 and §4.6, L4147): after the 180° port turn (25 m radius at 3 m/s, from
    t = 10 s) the depressor and fish of the two-part and series tows cut inside the ship's turning
    circle, and every towed body (parallel tow included) goes deeper than in steady tow."""
    sim = towenv.Simulator(name)
    depth0 = {b.name: -sim.body_state(b.name)["position"][2] for b in sim.system.bodies}
    sim.advance(10.0)
    centre = sim.positions[sim.system.top_node, :2] + np.array([0.0, 25.0])
    deepest = dict(depth0)
    closest = {b.name: np.inf for b in sim.system.bodies}
    for _ in range(60):
        sim.advance(1.0)
        for b in sim.system.bodies:
            p = sim.body_state(b.name)["position"]
            deepest[b.name] = max(deepest[b.name], -p[2])
            closest[b.name] = min(closest[b.name], np.linalg.norm(p[:2] - centre))
    for b in sim.system.bodies:
        if inside_expected:
            assert closest[b.name] < 25.0, f"{b.name} never inside the turning circle"
        assert deepest[b.name] > depth0[b.name] + 0.5, f"{b.name} did not deepen"


# --------------------------------------------------------------------------------------------------
# series tows: relaxation of the body–tail coupling (kernels.aft_segment_stiffness, docs/model-notes.md)
def test_tail_mass_is_everything_below_the_aft_tow_point():
    """system.tail_masses: the depressor's tail carries both sub-cables and both fish, fish 2's tail only
    sub-cable 1 and fish 1 (cable dry mass + body mass + largest added mass); fish 1 has no aft point."""
    sim = towenv.Simulator("series_multitow")
    s = sim.system
    sc = towenv.load_scene("series_multitow")
    lines = {ln.name: ln for ln in sc.lines}
    bodies = {b.name: b for b in sc.bodies}

    def cable(name):
        return lines[name].mass_per_length * lines[name].length

    def body(name):
        return bodies[name].mass + max(bodies[name].added_mass)

    by_name = {b.name: b.rigid_index for b in s.bodies if b.rigid_index >= 0}
    assert s.bp[by_name["fish2"], 30] == pytest.approx(cable("sub_cable_1") + body("fish1"), rel=1e-12)
    assert s.bp[by_name["depressor"], 30] == pytest.approx(
        cable("sub_cable_1") + cable("sub_cable_2") + body("fish1") + body("fish2"), rel=1e-12)
    assert s.bp[by_name["fish1"], 30] == 0.0


def test_series_relaxation_changes_the_rate_not_the_converged_step():
    """One Houbolt step of series_multitow (from a state 5 s into the sinusoid run) solved by the numpy
    twin to a tight tolerance with and without the body–tail relaxation: the same converged state (both
    converge at Δt = 0.02 s), while at Δt = 0.05 s only the relaxed iteration converges — the unrelaxed
    one's gain is about m_tail/m_body = 1.3 > 1 for fish 2, whose tail outweighs it. (The relaxed series
    coupling, solver.series_coupling = "relaxed"; the default monolithic one: tests/unit/test_series_coupling.py.)"""
    from towenv.verification import twin

    for dt, unrelaxed_converges in ((0.02, True), (0.05, False)):
        sim = towenv.Simulator("series_multitow", dt=dt, **{"solver.series_coupling": "relaxed"})
        sim.advance(5.0)
        sim.settings.tolerance = 1e-7           # N
        sim.settings.relative_tolerance = 1e-12
        sim.settings.angle_tolerance = 1e-12
        sim.settings.max_iterations = 200
        top = sim._tow_points(sim.step_count + 1, 1)[0]
        relaxed = twin.houbolt_step_np(sim, dt, top)
        assert relaxed.status == twin.OK
        orig = twin.aft_relaxation_np
        try:
            twin.aft_relaxation_np = lambda *a, **k: (np.zeros((3, 3)), np.zeros(3))
            plain = twin.houbolt_step_np(sim, dt, top)
        finally:
            twin.aft_relaxation_np = orig
        if unrelaxed_converges:
            assert plain.status == twin.OK
            assert np.abs(plain.hist_r[0] - relaxed.hist_r[0]).max() < 1e-9
            assert np.abs(plain.tens_hist[0] - relaxed.tens_hist[0]).max() < 1e-6
            assert relaxed.iterations <= plain.iterations
        else:
            assert plain.status != twin.OK


def test_series_tows_run_at_long_time_steps_without_step_cuts():
    """series_multitow in the Table 4.1 sinusoid: at Δt = 0.1 s (5× the scene's step) the Newton
    iteration converges on every step without cuts (before the relaxation: 1617 cuts in 120 s), and fish
    1's heave standard deviation agrees with Δt = 0.02 s to 0.5 % (measured 0.11 %)."""
    out = {}
    for dt in (0.02, 0.1):
        sim = towenv.Simulator("series_multitow", dt=dt)
        res = towenv.simulate(sim, 90.0)
        out[dt] = (sim.stats, np.std(res.bodies["fish1"]["heave"][res.t >= 30.0]))
    assert out[0.1][0]["step_cuts"] == 0
    assert out[0.1][0]["mean_iterations"] < 4
    assert out[0.1][1] == pytest.approx(out[0.02][1], rel=5e-3)
