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
