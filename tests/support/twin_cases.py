"""Scenes and helpers shared by the kernel-vs-twin tests (tests/verification/test_twin.py) and the tests that
reuse its cases (attitude, reduced models). Importable as ``twin_cases`` (pytest ``pythonpath = tests/support``)."""
from __future__ import annotations

import copy
import math  # noqa: F401
from unittest import mock

import numpy as np

from towenv.core import kernels as K
from towenv.core import simulator as simmod
from towenv.verification import twin


RTOL = 1e-12

# ----------------------------------------------------------------------------------------------
# scenes (plain dicts, docs/scene-format.md)
# ----------------------------------------------------------------------------------------------
# small illustrative coefficient tables (not from any measurement). The lift tables are deliberately
# nearly flat in incidence (the depressor's is a constant negative offset) so that the test scenes stay
# well damped whatever the sign convention of the incidence angle; they only have to exercise the code.
FISH_TAB = dict(incidence_deg=[0, 5, 10, 15, 20, 25], drag=[0.3, 0.32, 0.38, 0.48, 0.62, 0.8],
                lift=[0, 0.01, 0.03, 0.04, 0.05, 0.06], moment=[0, 0.05, 0.1, 0.15, 0.2, 0.25])
FISH_HTAB = dict(incidence_deg=[0, 10, 20, 30], drag=[0.3, 0.36, 0.55, 0.9],
                 lift=[0, 0.02, 0.04, 0.05], moment=[0, 0.08, 0.15, 0.2])
DEP_TAB = dict(incidence_deg=[-25, -15, -5, 0, 5, 15, 25], drag=[0.9, 0.6, 0.45, 0.4, 0.45, 0.6, 0.9],
               lift=[-1.18, -1.21, -1.2, -1.2, -1.2, -1.19, -1.22], moment=[-0.3, -0.2, -0.06, 0, 0.06, 0.2, 0.3])
CURRENT = dict(depths=[0.0, 20.0, 60.0], velocities=[[0.3, 0.1, 0.0], [0.1, -0.2, 0.0], [0.0, 0.05, 0.0]])
EXCITATION = [dict(type="sinusoid", axis="x", amplitude=0.3, period=6.0),
              dict(type="sinusoid", axis="z", amplitude=0.6, period=5.0, phase_deg=30.0)]
RAMP = dict(type="half_cosine", duration=1.0)


def _cable(name, length, segments, top, bottom):
    return dict(name=name, length=length, segments=segments, diameter=0.015, mass_per_length=0.6, EA=1.5e7,
                cn=1.2, ct=0.02, can=1.0, cat=0.1, top=top, bottom=bottom)


def _fish(name, **kw):
    d = dict(name=name, kind="fish", mass=41.2, volume=0.035, inertia=[0.2, 4.0, 4.0], cg=[-0.5, 0.0, -0.02],
             cb=[-0.5, 0.0, 0.0], added_mass=[3.0, 35.0, 35.0], added_inertia=[0.0, 3.0, 3.0],
             reference_area=0.0314, reference_length=1.2, coefficients=FISH_TAB,
             rotational_damping=[0.1, 0.2, 0.2], quadratic_rotational_damping=[0.5, 0.6, 0.6])
    d.update(kw)
    return d


def _depressor(name):
    return dict(name=name, kind="depressor", mass=300.0, volume=0.05, inertia=[20.0, 30.0, 40.0],
                cg=[-0.3, 0.0, -0.1], cb=[-0.3, 0.0, 0.0], added_mass=[20.0, 60.0, 200.0],
                added_inertia=[10.0, 20.0, 10.0], reference_area=0.5, reference_length=1.0, coefficients=DEP_TAB)


def _scene(name, lines, bodies, dt=0.02, speed=3.0, excitation=(), **solver):
    return dict(name=name, current=copy.deepcopy(CURRENT),
                vessel=dict(speed=speed, excitation=list(excitation), ramp=dict(RAMP)),
                lines=lines, bodies=bodies, solver=dict(dt=dt, **solver))


def two_part_scene(**kw):
    return _scene("two_part",
                  [_cable("primary", 85.0, [6, 2], "vessel", {"body": "depressor"}),
                   _cable("secondary", 20.0, 4, {"line": "primary", "distance": 65.0}, {"body": "fish"})],
                  [_fish("fish"), _depressor("depressor")], **kw)


def parallel_scene(**kw):
    """One primary with three secondaries: two at one junction (a 4-segment node) and one further down."""
    lines = [_cable("primary", 90.0, 9, "vessel", {"body": "depressor"})]
    for k, dist in enumerate((50.0, 50.0, 70.0)):
        lines.append(_cable(f"secondary{k}", 15.0 + 5 * k, 3, {"line": "primary", "distance": dist},
                            {"body": f"fish{k}"}))
    bodies = [_depressor("depressor")] + [_fish(f"fish{k}", mass=41.2 + 5 * k) for k in range(3)]
    return _scene("parallel", lines, bodies, **kw)


def series_scene(**kw):
    """A fish with an aft tow point towing a tail cable to a drogue ball (separate horizontal table)."""
    lines = [_cable("tow", 60.0, 6, "vessel", {"body": "lead"}),
             _cable("tail", 20.0, 4, {"body": "lead"}, {"body": "drogue"})]
    bodies = [_fish("lead", mass=120.0, volume=0.09, inertia=[1.0, 12.0, 12.0], cg=[-0.6, 0.01, -0.05],
                    cb=[-0.6, 0.0, 0.01], aft_tow_point=[-1.2, 0.0, -0.05], horizontal_coefficients=FISH_HTAB),
              dict(name="drogue", kind="ball", mass=30.0, volume=0.01, drag_area=0.3, added_mass_coefficient=0.5)]
    return _scene("series", lines, bodies, **kw)


def chain_scene(n=40):
    return _scene("chain", [dict(name="chain", length=float(n), segments=n, diameter=0.02, mass_per_length=1.0,
                                 EA=1.0e6, top="vessel", bottom="free")], [], speed=0.0)


#: a full 6x6 added mass about a point aft of the tow point (heave-pitch and sway-yaw coupling), with the
#: added mass's Coriolis/centripetal terms and Munk moment on (issue 18, item 1)
FISH_ADDED_MASS_MATRIX = [[3.0, 0.0, 0.4, 0.0, 0.0, 0.0],
                          [0.0, 35.0, 0.0, 0.3, 0.0, 2.0],
                          [0.4, 0.0, 35.0, 0.0, -1.5, 0.0],
                          [0.0, 0.3, 0.0, 0.5, 0.0, 0.0],
                          [0.0, 0.0, -1.5, 0.0, 3.0, 0.0],
                          [0.0, 2.0, 0.0, 0.0, 0.0, 3.0]]


def kirchhoff_scene(**kw):
    """The two-part tow with the fish's added mass as a full matrix about (−0.5, 0, 0) and the Kirchhoff terms."""
    sc = two_part_scene(**kw)
    fish = sc["bodies"][0]
    fish.update(added_mass=[0.0, 0.0, 0.0], added_inertia=[0.0, 0.0, 0.0],
                added_mass_matrix=copy.deepcopy(FISH_ADDED_MASS_MATRIX), added_mass_reference=[-0.5, 0.0, 0.0],
                added_mass_coriolis=True)
    sc["name"] = "kirchhoff"
    return sc


def splice_scene(**kw):
    """A heavy tow cable spliced to a lighter, thicker, softer one that carries the fish (issue 18, item 3); the fish
    has a constant thruster force (``external_force``)."""
    lower = _cable("lower", 30.0, 4, {"splice": "tow"}, {"body": "fish"})
    lower.update(diameter=0.03, mass_per_length=0.9, EA=2.0e6, cn=1.5)
    return _scene("splice", [_cable("tow", 60.0, 6, "vessel", "free"), lower],
                  [_fish("fish", external_force=[4.0, -2.0, -15.0])], **kw)


SCENES = {"two_part": two_part_scene, "parallel": parallel_scene, "series": series_scene,
          "kirchhoff": kirchhoff_scene, "splice": splice_scene}


def _simulator(scene):
    """A Simulator from a plain dict: through towenv.scene.load_scene when it exists, else unvalidated."""
    try:
        import towenv.scene  # noqa: F401
    except ImportError:
        with mock.patch.object(simmod, "load", lambda sc, ov=None: sc):
            return simmod.Simulator(scene)
    return simmod.Simulator(scene)


def kernel_and_twin_step(sim):
    """One Houbolt step of ``sim`` by the kernel (in place) and by the numpy twin from the same state: same
    status and iterations, states equal to 1e-9 of their size. Returns the twin's step."""
    top = sim.path.position(np.array([sim.t + sim.dt]))[0]
    res = twin.houbolt_step_np(sim, sim.dt, top)
    st, it, el, md = K.houbolt_step_entry(sim.dt, top, *sim._args, sim.settings.array(), sim._state, sim._ws, sim.comp)
    assert st == K.OK and res.status == twin.OK and it == res.iterations
    for key in ("hist_r", "tens_hist", "hist_ang", "top_react"):
        a, b = getattr(res, key), getattr(sim, key)
        assert np.max(np.abs(a - b)) <= 1e-9 * max(np.max(np.abs(b)), 1e-30), key
    return res
