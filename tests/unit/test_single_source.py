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
    assert np.allclose(b.bodyp()[0][0, 13:16], RigidBody.model_fields["rotational_damping"].default)
    assert np.array_equal(a.bodyp()[0], b.bodyp()[0])
    assert np.array_equal(a.segp()[0], b.segp()[0]) and a.rho == b.rho and a.g == b.g


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
