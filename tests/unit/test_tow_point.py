"""Issue 15: the Simulator's tow-point path in a sea uses the phase recurrence the environments use
(towenv.core.tow_point) — equal to the exact sum of the wave components to 1e-9 m over 3000 s, independent
of how a run is chunked, and the same numbers the environments' buffer gives."""
import numpy as np

import towenv
from towenv.core.tow_point import TowPointBuffer


def test_simulator_tow_points_are_the_fast_path_and_match_the_exact_path():
    sim = towenv.Simulator("two_part_coastal_ss4")
    assert TowPointBuffer(sim)._linear(0.0, 1.0) is not None        # a sea on a straight leg: recurrence used
    dt = sim.dt
    for first in (1, 5, 129, 1000, 6000, 60_000):                    # up to 3000 s at Δt = 0.05 s
        got = sim._tow_points(first, 300)
        exact = sim.path.position((first + np.arange(300)) * dt)
        assert np.abs(got - exact).max() < 1e-9
        # chunking independence, and the environments' buffer gives the same numbers bit for bit
        np.testing.assert_array_equal(sim._tow_points(first + 7, 100), got[7:107])
        np.testing.assert_array_equal(TowPointBuffer(sim).block(first, 300), got)


def test_a_run_does_not_depend_on_how_it_is_chunked_in_a_sea():
    a = towenv.Simulator("two_part_coastal_ss4")
    b = towenv.Simulator("two_part_coastal_ss4")
    a.advance_steps(300)
    for n in (1, 127, 2, 170):
        b.advance_steps(n)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.tensions, b.tensions)


def test_set_sea_uses_the_new_sea():
    sim = towenv.Simulator("two_part_coastal_ss4")
    before = sim._tow_points(1, 200)
    sim.set_sea({"convention": "coastal", "code": 5}, seed=11)
    after = sim._tow_points(1, 200)
    exact = sim.path.position((1 + np.arange(200)) * sim.dt)
    assert np.abs(after - exact).max() < 1e-9 and np.abs(after - before).max() > 1e-3


def test_one_aligned_block_with_its_mean_track_equals_the_general_path():
    """The stepper's refill (one aligned block with its mean track, issue 15's cheaper refill) gives the numbers
    of the general chunked path bit for bit; and ``mean_path`` on one piece equals its per-piece evaluation."""
    from towenv.core.tow_point import BLOCK
    sim = towenv.Simulator("two_part_coastal_ss4")
    dt = sim.dt
    for first, count in ((0, BLOCK), (5 * BLOCK, BLOCK), (7 * BLOCK, 40)):
        tp = TowPointBuffer(sim)
        pos, mean = tp.block(first, count, mean=True)
        np.testing.assert_array_equal(pos, tp._aligned(first, count))
        t = np.arange(first, first + count) * dt
        x, psi, _ = sim.path.mean_path(t)
        np.testing.assert_array_equal(mean, np.column_stack([x, psi]))
        # the general path (not aligned: chunk by chunk) for the same steps
        np.testing.assert_array_equal(tp.block(first + 1, count - 1), pos[1:])
    # mean_path across two pieces of a manoeuvre (masked per piece) equals it on each piece alone
    turn = towenv.Simulator("ablow_turn_1km")
    path = turn.path
    assert len(path.pieces) > 1
    t0 = path.pieces[1].t0
    t = np.linspace(t0 - 5.0, t0 + 5.0, 41)
    both = path.mean_path(t)
    lo, hi = t < t0, t >= t0
    for part in (lo, hi):
        one = path.mean_path(t[part])
        for a, b in zip(both, one):
            np.testing.assert_array_equal(a[part], b)


def test_an_exact_path_is_evaluated_in_one_call_per_block_with_the_same_bits():
    """Without a sea-state vessel motion (here the peer deck's sinusoidal heave) no block can use the recurrence:
    the buffer evaluates a whole range in one ``path.position`` call (was one call per 128 steps, ~50 µs of numpy
    calls each) and the Simulator keeps its long block at every Δt — the same numbers, bit for bit, as the
    evaluation 128 steps at a time."""
    from towenv.core.tow_point import BLOCK
    from towenv.peer.decks import shared_deck
    sim = towenv.make_simulator(shared_deck(segments=20), method="houbolt", dt=0.05)
    buf = TowPointBuffer(sim)
    assert not buf.recurrence_possible()
    assert TowPointBuffer(towenv.Simulator("two_part_coastal_ss4")).recurrence_possible()
    n = 2 * sim._BLOCK + 77
    one = buf.block(0, n)
    by_block = np.concatenate([buf._aligned(s, min(BLOCK, n - s)) for s in range(0, n, BLOCK)])
    np.testing.assert_array_equal(one, by_block)
    pos, mean = buf.block(5, 300, mean=True)
    np.testing.assert_array_equal(pos, one[5:305])
    x, psi, _ = sim.path.mean_path(np.arange(5, 305) * sim.dt)
    np.testing.assert_array_equal(mean, np.column_stack([x, psi]))
    calls = []
    position = sim.path.position
    sim.path.position = lambda t: calls.append(len(t)) or position(t)
    sim.advance_steps(1600)                                  # the deck's 80 s at Δt = 0.05 s: one block
    assert calls == [sim._BLOCK]
    np.testing.assert_array_equal(sim._tow_points(1, 1600), one[1:1601])


def test_the_block_length_follows_set_sea_without_stale_blocks():
    """The Simulator's block length depends on whether the path can use the recurrence (256 steps in a sea at
    Δt 0.05 s, 2048 on an exact path): switching the sea off and on again must not serve a block cached under the
    other length (set_sea drops the cache)."""
    sim = towenv.Simulator("two_part_coastal_ss4")
    assert sim.dt >= 0.05
    steps = 1 + np.arange(600)
    for sea in (None, {"convention": "coastal", "code": 5}, None):
        sim.set_sea(sea, seed=3)
        got = sim._tow_points(1, 600)
        exact = sim.path.position(steps * sim.dt)
        assert np.abs(got - exact).max() < 1e-9
        assert sim._tow_point_buffer().recurrence_possible() is (sea is not None)


def test_a_span_of_blocks_equals_its_blocks_bit_for_bit():
    """``TowPointBuffer.span`` (the stepper's refill: several aligned blocks with their exact anchors in one
    vectorised call) gives the positions and mean track of ``block`` block by block, bit for bit — on a straight
    leg (the vectorised anchors are used) and across a turn in a sea (the span falls back to block by block)."""
    from towenv.core.tow_point import BLOCK
    straight = towenv.Simulator("two_part_coastal_ss4")
    scene = towenv.load_scene("two_part_coastal_ss4").with_overrides(
        **{"vessel.manoeuvres": [{"type": "turn", "start_time": 40.0, "radius": 300.0, "angle_deg": 90.0}]})
    turning = towenv.Simulator(scene)
    for sim, firsts in ((straight, (0, 4 * BLOCK, 37 * BLOCK)), (turning, (0, 4 * BLOCK, 40 * BLOCK))):
        dt = sim.dt
        for first in firsts:
            tp = TowPointBuffer(sim)
            assert tp.recurrence_possible()
            pos, mean = tp.span(first, 4)
            assert pos.shape == (4 * BLOCK, 3) and mean.shape == (4 * BLOCK, 4)
            parts = [TowPointBuffer(sim).block(first + k * BLOCK, BLOCK, mean=True) for k in range(4)]
            np.testing.assert_array_equal(pos, np.concatenate([p for p, _m in parts]))
            np.testing.assert_array_equal(mean, np.concatenate([m for _p, m in parts]))
            t = (first + np.arange(4 * BLOCK)) * dt
            assert np.abs(pos - sim.path.position(t)).max() < 1e-9
            vectorised = tp._linear_anchors(t[::BLOCK], float(t[-1])) is not None
            in_turn = sim is turning and t[0] < 40.0 + 300.0 * np.pi / 2 / sim.path.pieces[1].speed and t[-1] > 40.0
            assert vectorised is not in_turn


def test_span_refuses_unaligned_starts():
    import pytest
    tp = TowPointBuffer(towenv.Simulator("two_part_coastal_ss4"))
    for first, nblocks in ((5, 4), (128, 0)):
        with pytest.raises(ValueError, match="multiple of 128 and nblocks >= 1"):
            tp.span(first, nblocks)


def test_the_stepper_refills_a_span_at_a_time():
    """An environment's tow-point buffer is refilled once per SPAN physics steps (was once per BLOCK), with the
    positions the Simulator computes for the same steps."""
    import gymnasium as gym
    import towenv.envs  # noqa: F401
    from towenv.envs import stepper as ST
    env = gym.make("towenv/CompensatorGains-v0").unwrapped
    env.reset(seed=2, options={"eval_index": 4})
    st = env._rows.stepper
    tp = st._tp[0]
    calls = []
    span = tp.span
    tp.span = lambda first, n: calls.append((first, n)) or span(first, n)
    steps = 0
    for _ in range(700):
        env.step(np.zeros(env.action_space.shape, np.float32))
        steps += env.substeps
    assert steps > 2 * ST.SPAN
    # the reset filled steps 0 … SPAN−1; a refill when a control step first needs step k·SPAN
    assert calls == [(k * ST.SPAN, ST.SPAN_BLOCKS) for k in range(1, steps // ST.SPAN + 1)]
    sim = st.sims[0]
    base = int(st._base[0])
    np.testing.assert_array_equal(st._blk[0], TowPointBuffer(sim).block(base, 2 * ST.SPAN))


def test_a_stepper_pickled_with_block_sized_buffers_refills_and_continues_the_same_trajectory():
    """A stepper pickled before the span refill (buffers of 2·BLOCK rows) is given buffers of the current size on
    unpickling and refills them on its next step: the environment continues the uninterrupted run bit for bit."""
    import pickle
    import gymnasium as gym
    import towenv.envs  # noqa: F401
    from towenv.envs import stepper as ST
    acts = np.random.default_rng(9).uniform(-1, 1, (700, 2)).astype(np.float32)
    ref = gym.make("towenv/CompensatorGains-v0").unwrapped
    ref.reset(seed=5, options={"eval_index": 2})
    want = [ref.step(a)[0] for a in acts]
    env = gym.make("towenv/CompensatorGains-v0").unwrapped
    env.reset(seed=5, options={"eval_index": 2})
    got = [env.step(a)[0] for a in acts[:300]]
    st = env._rows.stepper
    state = st.__getstate__()
    B = st.num_copies
    state["_blk"], state["_mblk"] = np.zeros((B, 2 * ST.BLOCK, 3)), np.zeros((B, 2 * ST.BLOCK, 4))   # the old layout
    st.__setstate__(state)                     # as an unpickled earlier stepper
    assert st._blk.shape == (B, 2 * ST.SPAN, 3) and not st._filled.any()
    env2 = pickle.loads(pickle.dumps(env))
    got += [env2.step(a)[0] for a in acts[300:]]
    np.testing.assert_array_equal(np.array(got), np.array(want))
