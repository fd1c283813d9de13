"""Spliced lines (issue 18, item 3): ``top = {splice = "upper"}`` continues line ``upper`` from its free bottom end at
a shared node, with different properties either side, solved in the same tree tension solve.

* a uniform cable cut into two spliced lines is the same discrete model as the single line — same statics and
  same dynamics, bit for bit (same node order, same arithmetic);
* a spliced cable of piecewise properties hanging vertically has the closed-form static tensions (each segment
  carries the wet weight below it) to 1e-9; its dynamics against the numpy twin are in tests/verification/test_twin.py
  (scene ``splice``);
* bad splices are refused naming the field.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import towenv
from towenv.scene import SceneError, load_scene

RHO, G = 1025.0, 9.81
EXCITATION = [dict(type="sinusoid", axis="z", amplitude=0.5, period=6.0),
              dict(type="sinusoid", axis="x", amplitude=0.3, period=8.0)]


def _cable(name, length, segments, top, bottom, **kw):
    d = dict(name=name, length=length, segments=segments, diameter=0.0173, mass_per_length=1.04, EA=9.87e6, cn=1.2,
             ct=0.01, can=1.0, cat=0.0, top=top, bottom=bottom)
    d.update(kw)
    return d


def _scene(lines, speed=2.0, excitation=EXCITATION):
    return dict(name="splice", water=dict(density=RHO, gravity=G), vessel=dict(speed=speed, excitation=excitation),
                lines=lines, bodies=[dict(name="weight", kind="clump", mass=200.0, volume=0.01, drag_area=0.2,
                                          added_mass_coefficient=0.5)],
                solver=dict(dt=0.05))


def test_uniform_splice_is_the_single_line_bit_for_bit():
    """100 m in 10 segments as one line, and as 60 m (6) spliced to 40 m (4): statics, then 30 s of towing at 2 m/s
    with surge and heave at the top, identical to the last bit (positions and tensions)."""
    one = towenv.Simulator(_scene([_cable("one", 100.0, 10, "vessel", {"body": "weight"})]))
    two = towenv.Simulator(_scene([_cable("upper", 60.0, 6, "vessel", "free"),
                                   _cable("lower", 40.0, 4, {"splice": "upper"}, {"body": "weight"})]))
    assert np.array_equal(one.positions, two.positions) and np.array_equal(one.tensions, two.tensions)
    one.advance(30.0)
    two.advance(30.0)
    assert np.array_equal(one.hist_r, two.hist_r) and np.array_equal(one.tens_hist, two.tens_hist)
    up, low = two.line_state("upper"), two.line_state("lower")
    assert np.array_equal(up["positions"][-1], low["positions"][0])          # the shared node
    assert up["tensions"].size == 6 and low["tensions"].size == 4


def test_piecewise_spliced_cable_hangs_with_the_closed_form_tensions():
    """At rest, a heavy 60 m armoured cable spliced to a 40 m buoyant-jacketed one of another diameter, mass and
    EA, with a 200 kg clump: in the lumped-mass model each node carries half of each adjacent segment's wet weight,
    so segment k's tension is the clump's wet weight + the wet weight of every segment below k + half of k's own —
    to 1e-9 relative (the statics' tolerance), and every node lies on the vertical below the tow point."""
    lower = dict(diameter=0.05, mass_per_length=1.5, EA=2.0e6)
    sc = _scene([_cable("upper", 60.0, 6, "vessel", "free"),
                 _cable("lower", 40.0, 5, {"splice": "upper"}, {"body": "weight"}, **lower)], speed=0.0, excitation=[])
    sim = towenv.Simulator(sc)
    w_up = (1.04 - RHO * math.pi * 0.0173 ** 2 / 4) * G * 10.0           # wet weight per segment, N
    w_low = (1.5 - RHO * math.pi * 0.05 ** 2 / 4) * G * 8.0
    assert w_low < 0.0 < w_up                                            # a buoyant lower part: a real splice
    W = (200.0 - RHO * 0.01) * G
    seg_w = np.r_[np.full(6, w_up), np.full(5, w_low)]
    expected = np.array([W + seg_w[k + 1:].sum() + 0.5 * seg_w[k] for k in range(11)])
    got = np.r_[sim.line_state("upper")["tensions"], sim.line_state("lower")["tensions"]]
    np.testing.assert_allclose(got, expected, rtol=1e-9)
    assert np.max(np.abs(sim.positions[:, :2])) < 1e-9 * 100.0


@pytest.mark.parametrize("lines, field, words", [
    ([_cable("upper", 60.0, 6, "vessel", "free"), _cable("lower", 40.0, 4, {"splice": "nope"}, {"body": "weight"})],
     "lines[1].top.splice", "unknown line"),
    ([_cable("upper", 60.0, 6, "vessel", {"body": "weight"}), _cable("lower", 40.0, 4, {"splice": "upper"}, "free")],
     "lines[1].top.splice", "must end free"),
    ([_cable("upper", 60.0, 6, "vessel", "free"), _cable("lower", 40.0, 4, {"splice": "upper"}, {"body": "weight"}),
      _cable("other", 10.0, 2, {"splice": "upper"}, "free")], "lines[2].top.splice", "already continued"),
    ([_cable("upper", 60.0, 6, "vessel", {"body": "weight"}), _cable("loop", 10.0, 2, {"splice": "loop"}, "free")],
     "lines[1].top.splice", "itself"),
])
def test_bad_splices_are_refused_naming_the_field(lines, field, words):
    with pytest.raises(SceneError) as e:
        load_scene(_scene(lines))
    assert field in str(e.value) and words in str(e.value)


def test_splice_round_trips_through_toml(tmp_path):
    sc = load_scene(_scene([_cable("upper", 60.0, 6, "vessel", "free"),
                            _cable("lower", 40.0, 4, {"splice": "upper"}, {"body": "weight"})]))
    assert sc.line("lower").top_kind == "splice"
    p = tmp_path / "s.toml"
    p.write_text(sc.to_toml())
    assert load_scene(p).to_dict() == sc.to_dict()
