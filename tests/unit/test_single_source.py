"""Issue 16, item 4: the validated Scene is the one source of every default the core uses."""
import dataclasses
import inspect

import numpy as np

import towenv
from towenv.core import excitation, simulator, system
from towenv.core.simulator import SolverSettings
from towenv.scene import Solver, load_scene, scene_field


def test_solver_settings_defaults_are_the_schema_defaults():
    shared = [f.name for f in dataclasses.fields(SolverSettings) if f.name in Solver.model_fields]
    assert len(shared) >= 10
    for name in shared:
        assert getattr(SolverSettings(), name) == Solver.model_fields[name].default, name
    # every scene solver setting is accepted by the factory as a short override
    sim = towenv.make_simulator("two_part_tow_1", max_iterations=31, newton_stop="estimate")
    assert sim.settings.max_iterations == 31 and sim.settings.newton_stop == "estimate"


def test_one_scene_accessor():
    for mod in (excitation, simulator, system):
        assert mod._get is scene_field, mod.__name__
        assert "def _get(" not in inspect.getsource(mod)


def test_build_system_reads_the_validated_scene():
    sc = load_scene("two_part_tow_1")
    d = sc.model_dump()
    for body in d["bodies"]:            # leave the optional fields out: the schema's defaults must apply
        for k in ("rotational_damping", "quadratic_rotational_damping", "added_inertia", "dof"):
            body.pop(k, None)
    a, b = system.build_system(load_scene(d)), system.build_system(d)
    from towenv.scene import RigidBody
    rigid = [i for i, bd in enumerate(d["bodies"]) if bd.get("kind") in ("fish", "depressor")]
    assert rigid
    from towenv.core.layout import BP_ROT_DAMPING
    assert np.allclose(b.bodyp().bp[0, BP_ROT_DAMPING:BP_ROT_DAMPING + 3],
                       RigidBody.model_fields["rotational_damping"].default)
    assert np.array_equal(a.bodyp().bp, b.bodyp().bp)
    assert np.array_equal(a.segp().l0, b.segp().l0) and a.rho == b.rho and a.g == b.g


def test_body_parameter_columns_are_named_outside_the_layout():
    """Issue 16, item 1 (part): no raw column numbers into ``System.bp`` outside towenv/core/layout.py."""
    import re
    from pathlib import Path
    root = Path(system.__file__).resolve().parents[1]
    raw = re.compile(r"\b(bp|bodyp\[0\])\[[^\[\],]+, *\d|\bsettings\[\d")
    hits = [f"{p.relative_to(root)}:{i}" for p in root.rglob("*.py") if p.name != "layout.py"
            for i, line in enumerate(p.read_text().splitlines(), 1) if raw.search(line) and "``" not in line
            and not line.lstrip().startswith("#")]
    assert not hits, hits
    from towenv.core import layout
    cols = sorted(v for k, v in vars(layout).items() if k.startswith("BP_"))
    assert cols[-1] == layout.BODY_PARAM - 1 and len(set(cols)) == len(cols)


def test_kernel_structures_are_read_by_name():
    """Issue 16, item 1: the kernels' structures (towenv.core.model) are read by field name — no positional
    index into the topology, segment, body, water, state, work, saved-step, α-state or gathered tuples, and
    no raw counter numbers, in the modules that handle them (core, envs, verification, linear)."""
    import re
    from pathlib import Path
    root = Path(system.__file__).resolve().parents[1]
    raw = re.compile(r"\b(topo|segp|bodyp|env|state|ws|work|saved|st|tr|st_tr|bk|g|counters|_ws|_state|_saved|_tr|_st)"
                     r"(\(\))?\[\d")
    files = [p for d in ("core", "envs", "verification", "linear") for p in (root / d).rglob("*.py")]
    hits = [f"{p.relative_to(root)}:{i}: {line.strip()}" for p in files if p.name != "layout.py"
            for i, line in enumerate(p.read_text().splitlines(), 1) if raw.search(line) and "``" not in line
            and not line.lstrip().startswith("#")]
    assert not hits, hits


def test_model_structures_match_the_arrays_they_name():
    """Each named structure holds what its fields say, for a scene with junction, bodies and a sea."""
    from towenv.core import model
    sim = towenv.make_simulator("two_part_coastal_ss4")
    s = sim.system
    kd = sim.kernel_data()
    top_node, topo, seg, bodies, water = kd.args
    assert isinstance(topo, model.Topology) and topo.seg_lo is s.seg_lo and topo.body_aft_node is s.body_aft_node
    assert isinstance(seg, model.Segments) and seg.ea is s.ea and seg.l0 is s.l0
    assert isinstance(bodies, model.Bodies) and bodies.bp is s.bp and bodies.pb_ca is s.pb_ca
    assert isinstance(water, model.Water) and water.rho == s.rho and water.cur_v is s.cur_v
    assert isinstance(kd.state, model.TimeLevels) and kd.state.hist_r is sim.hist_r and kd.state.chart is sim.body_chart
    w = kd.work
    assert isinstance(w, model.HouboltWork)
    nn, ns, nb = s.n_nodes, s.n_segments, s.n_rigid
    assert w.tang.shape == (ns, 3) and w.kb.shape == (nn, model.MAX_SEGS_PER_NODE, model.MAX_SEGS_PER_NODE)
    assert w.blam.shape == (nb, 3, 3) and w.flow.shape == (nn, 3) and w.bkc.shape == (max(nb, 1), 9)
    assert isinstance(kd.saved, model.SavedStep) and kd.saved.hist_r.shape == sim.hist_r.shape
    assert isinstance(kd.wave, model.WaveField)


def test_one_morison_drag_for_kernels_statics_and_linearisation():
    """Issue 16, item 2: the cable drag formula is written once (towenv.core.cable_loads.morison_drag and its
    Jacobian morison_damping); the statics and the linearisation call it, and it agrees with the independent
    numpy twin (to round-off) and with a finite-difference Jacobian."""
    from pathlib import Path
    from towenv.core import cable_loads, statics
    from towenv.linear import eqlin
    from towenv.verification.twin import morison_drag_np
    rng = np.random.default_rng(7)
    for _ in range(50):
        vr = rng.normal(size=3) * rng.choice([1e-3, 1.0, 5.0])
        t = rng.normal(size=3)
        t /= np.linalg.norm(t)
        kn, kt = rng.uniform(0.1, 50.0, 2)
        f = np.array(cable_loads.morison_drag(*vr, *t, kn, kt))
        B = np.zeros((1, 1, 3, 3))
        cable_loads.morison_damping(*vr, *t, kn, kt, B, 0, 0)
        f_np, B_np = morison_drag_np(vr, t, kn, kt)
        scale = max(1.0, np.abs(f_np).max())
        assert np.allclose(f, f_np, rtol=1e-12, atol=1e-12 * scale)
        assert np.allclose(B[0, 0], B_np, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(B_np).max()))
        h = 1e-6 * max(1.0, np.linalg.norm(vr))
        fd = np.column_stack([(np.array(cable_loads.morison_drag(*(vr + h * e), *t, kn, kt))
                               - np.array(cable_loads.morison_drag(*(vr - h * e), *t, kn, kt))) / (2 * h)
                              for e in np.eye(3)])
        assert np.allclose(-fd, B[0, 0], rtol=1e-5, atol=1e-6 * max(1.0, np.abs(B_np).max()))
        # the statics' whole-segment drag is the same formula with k = ½ρ C D l
        rho, diam, l0, cn, ct = 1025.0, 0.02, 3.0, 1.5, 0.01
        assert np.array_equal(statics._segment_drag(t, vr, rho, diam, l0, cn, ct),
                              np.array(cable_loads.morison_drag(*vr, *t, 0.5 * rho * cn * diam * l0,
                                                                0.5 * rho * ct * diam * l0)))
    # nobody else writes the formula: "kt * avt * vt" appears in cable_loads only (and the twin, on purpose)
    root = Path(cable_loads.__file__).resolve().parents[1]
    writers = sorted(str(p.relative_to(root)) for p in root.rglob("*.py")
                     if "* avt * vt" in p.read_text() or "abs(vt) * vt" in p.read_text())
    assert writers == ["core/cable_loads.py", "verification/twin.py"], writers
    assert eqlin.morison_drag is cable_loads.morison_drag and eqlin.morison_damping is cable_loads.morison_damping


def test_houbolt_step_is_split_into_phases_compiled_without_reference_counting():
    """Issue 16 item 2: houbolt_step is a driver of phase functions. They run without numba's reference
    counting: with it, the phases measured 11-45 % slower per step than the single function they replaced
    (docs/architecture.md), so losing the flag would be a silent speed loss."""
    from towenv.core import houbolt
    phases = ("actuator_lag", "predict", "iterate_coefficients", "node_local_solve", "tension_system",
              "tension_apply", "body_angle_update", "end_stop_contact", "commit")
    driver = inspect.getsource(houbolt.houbolt_step.py_func)
    for name in phases + ("houbolt_step",):
        f = getattr(houbolt, name)
        assert f.targetoptions.get("_nrt") is False, name
    for name in phases:
        assert f"{name}(" in driver, name
    # the driver holds no per-node or per-segment loop of its own: the work is in the phases
    assert "range(nn)" not in driver and "range(ns)" not in driver
