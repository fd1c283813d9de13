"""The monolithic series coupling (solver.series_coupling = "monolithic", the default): a body's aft tow point is
merged into its tow-point node's clique of the tree tension solve (system.tension_cliques), the tail's pull moves
the body through the condensation (H_b) and turns it (G_b), the body's rotation is in the Newton step
(houbolt.aft_point_influence) and its rotational stiffness and the aft node's inertia and damping (a point mass
at the aft point) are inside the condensation. It changes the iteration, not the converged solution; it lets a
light connector body carrying hundreds of metres of array run at long steps (issue 18, item 3)."""
import numpy as np
import pytest

import towenv
from towenv.core import kernels as K
from towenv.core.model import MAX_SEGS_PER_NODE
from towenv.core.system import tension_cliques
from towenv.validation.problems import series_connector_scene
from towenv.verification import twin


def _merged(sys):
    return [(int(sys.body_node[b]), int(sys.body_aft_node[b])) for b in range(sys.n_rigid) if sys.body_aft_node[b] >= 0]


def test_tension_tree_merges_each_aft_point_into_its_body_node():
    mono = towenv.Simulator("series_multitow").system
    relaxed = towenv.Simulator("series_multitow", **{"solver.series_coupling": "relaxed"}).system
    pairs = _merged(mono)
    assert len(pairs) == 2
    # relaxed: the tension tree is the cable topology
    for name in ("nseg", "segs", "sgn"):
        assert np.array_equal(getattr(relaxed, f"tn_{name}"), getattr(relaxed, f"node_{name}"))
    assert np.array_equal(relaxed.tseg_up, relaxed.seg_up)
    for a, c in pairs:
        own = list(mono.node_segs[a, :mono.node_nseg[a]])
        tail = list(mono.node_segs[c, :mono.node_nseg[c]])
        assert mono.tn_nseg[c] == 0 and np.all(mono.tn_segs[c] == -1)
        assert list(mono.tn_segs[a, :mono.tn_nseg[a]]) == own + tail
        assert np.all(mono.tn_sgn[a, len(own):mono.tn_nseg[a]] == -1.0)      # the aft point is their upper end
        for k, s in enumerate(tail):
            assert mono.tseg_up[s] == a and mono.tseg_uplocal[s] == len(own) + k
            assert mono.seg_up[s] == c                                      # the cable topology is unchanged
            # the elimination order stays valid: the tail before the segment above the body
            assert mono.pos[s] < mono.pos[mono.node_up_seg[a]]
    # too many segments at a body and its aft point together: a clear refusal naming the option
    nseg = mono.node_nseg.copy()
    a, c = pairs[0]
    nseg[a] = MAX_SEGS_PER_NODE
    with pytest.raises(ValueError, match="series_coupling"):
        tension_cliques(nseg, mono.node_segs, mono.node_sgn, mono.seg_up, mono.seg_uplocal, mono.body_node,
                        mono.body_aft_node, True)


def test_scene_field_is_validated():
    with pytest.raises(Exception, match="series_coupling"):
        towenv.Simulator("series_multitow", **{"solver.series_coupling": "gauss_seidel"})


def test_monolithic_and_relaxed_couplings_converge_to_the_same_solution():
    """series_multitow (Table 4.1 sinusoid), Δt = 0.05 s, 400 steps solved to a tight tolerance (1e-6 N, 1e-11 rad)
    with either coupling: the same trajectory (measured 4e-9 m, 6e-7 N of ~3 kN, 5e-10 rad) — the coupling is a
    property of the iteration, not of the discrete equations — and the monolithic one needs fewer iterations
    (measured 3.5 against 6.7 a step)."""
    sims = {}
    for mode in ("relaxed", "monolithic"):
        sim = towenv.Simulator("series_multitow", dt=0.05, tolerance=1e-6, relative_tolerance=0.0,
                               angle_tolerance=1e-11, max_iterations=100, **{"solver.series_coupling": mode})
        sim.advance(20.0)
        sims[mode] = sim
    a, b = sims["relaxed"], sims["monolithic"]
    assert np.abs(a.hist_r - b.hist_r).max() < 1e-7
    assert np.abs(a.tens_hist - b.tens_hist).max() < 1e-5 * a.tens_hist.max()
    assert np.abs(a.hist_ang - b.hist_ang).max() < 1e-8
    assert b.stats["mean_iterations"] < 0.75 * a.stats["mean_iterations"]


@pytest.mark.parametrize("heave", [0.0, 1.0])
def test_light_connector_runs_at_long_steps_without_step_cuts(heave):
    """Validation problem 2 (the Srivastava array's sections joined by two 50 kg connectors, 4 m/s, tail tension
    ~5 kN at the first connector), steady and with a 1 m vessel heave: 60 s at Δt = 0.1 s without a step cut
    (measured 1.00 and 2.00 Newton iterations a step). The relaxed coupling diverges on the same case (steady:
    at t = 3.2 s; heaving: 0.3 s) — what this test would catch if the coupling fell back to it."""
    sim = towenv.Simulator(series_connector_scene(0.1, heave=heave), max_step_cuts=0)
    sim.advance(60.0)
    assert sim.stats["step_cuts"] == 0 and sim.stats["max_iterations"] <= 3
    assert np.all(np.isfinite(sim.hist_r)) and np.isfinite(sim.top_tension)
    relaxed = towenv.Simulator(series_connector_scene(0.1, "relaxed", heave))
    with pytest.raises(towenv.SimulationDivergence):
        relaxed.advance(60.0)


def test_light_connector_steady_tow_stays_steady_and_its_heave_response_converges_in_the_step():
    """The connector's pitch mode (~1.8 Hz, damping ratio ~1 % in this model) is resolved at Δt ≤ 0.05 s, where the
    Newton stopping error could drive it. With the aft node's mass and damping in the condensation the iteration
    converges in one step of a steady tow: at Δt = 0.01 s and 0.02 s the steady tow stays steady at the default
    tolerance (measured pitch σ 0 over 50-70 s, 1.00 iterations a step; before that term, 0.2-1°). Under a 1 m
    heave the first connector's pitch σ agrees between Δt = 0.02 and 0.1 s (measured 0.1227° and 0.1237°)."""
    for dt in (0.01, 0.02):
        sim = towenv.Simulator(series_connector_scene(dt))
        res = towenv.simulate(sim, 70.0, 0.1)
        pitch = np.degrees(np.asarray(res.bodies["c1"]["euler"])[:, 1])
        assert np.std(pitch[res.t >= 50.0]) < 1e-4
        assert sim.stats["step_cuts"] == 0 and sim.stats["max_iterations"] <= 2
    sig = {}
    for dt in (0.02, 0.1):
        sim = towenv.Simulator(series_connector_scene(dt, heave=1.0))
        res = towenv.simulate(sim, 70.0, 0.1)
        pitch = np.degrees(np.asarray(res.bodies["c1"]["euler"])[:, 1])
        sig[dt] = np.std(pitch[res.t >= 50.0])
    assert sig[0.02] > 0.05
    assert abs(sig[0.1] / sig[0.02] - 1.0) < 0.05


def test_kernel_matches_twin_on_the_light_connector():
    """20 Houbolt steps of the heaving connector case at Δt = 0.1 s (several Newton iterations a step, both
    bodies merged): the kernel and the numpy twin take the same iterations to the same state (1e-8)."""
    sim = towenv.Simulator(series_connector_scene(0.1, heave=1.0))
    sim.advance(2.0)
    state = sim
    iters = []
    for _ in range(20):
        top = sim._tow_points(sim.step_count + 1, 1)[0]
        state = twin.houbolt_step_np(state, sim.dt, top)
        st, it, _, _ = K.houbolt_step_entry(sim.dt, top, *sim._args, sim.settings.array(), sim._state, sim._ws, sim.comp)
        sim.step_count += 1
        assert st == K.OK and state.status == twin.OK
        assert it == state.iterations
        iters.append(it)
    assert max(iters) >= 2
    scale = np.abs(sim.hist_r).max()
    assert np.abs(state.hist_r - sim.hist_r).max() < 1e-8 * scale
    assert np.abs(state.tens_hist - sim.tens_hist).max() < 1e-8 * sim.tens_hist.max()
    assert np.abs(state.hist_ang - sim.hist_ang).max() < 1e-8
