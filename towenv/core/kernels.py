"""The compiled kernels of the lumped-mass tow simulator, one import for callers.

Each kernel lives in the module of the physical object it handles; this module re-exports them (and the
layouts and codes of :mod:`towenv.core.layout`) so ``from towenv.core import kernels as K; K.advance(...)``
keeps working. Everything works on the named structures of :mod:`towenv.core.model` and flat arrays (see
:mod:`towenv.core.system` for their meaning). Each public kernel has a plain-numpy twin in
:mod:`towenv.verification.twin` that the tests compare against.

Where each force is computed (one search finds it):

* cable drag, weight, mass and added mass of a segment ...... ``cable_loads.segment_loads``
  (the Morison drag of one segment: ``cable_loads.morison_drag``, shared with the statics and the
  linearisation)
* assembly of node mass matrices and non-tension forces ....... ``cable_loads.node_assembly``
* point bodies (ball / clump) ................................. ``cable_loads.node_assembly`` (``pb_*`` arrays)
* rigid towed bodies: hydrodynamics, weight/buoyancy, damping ... ``body_dynamics.body_loads``
* condensation of a rigid body onto its tow-point node ........ ``body_dynamics.condense_body``
* the tension (length-constraint) system and its tree LDLᵀ .... ``tension_solve``
* heave compensator sheave, end stops; winch payout ........... ``actuators``
* wave orbital velocity at the nodes ......................... ``orbital_flow``
* one Houbolt step with the Newton iteration, ``advance`` ...... ``houbolt``
* rotations, attitude charts, Euler-angle rates .............. ``rotations``

Sign conventions: ``t_s`` is the unit tangent of segment ``s`` pointing from its lower node to its upper
node (toward the ship); a positive tension pulls the lower node by ``+T t`` and the upper node by
``-T t``. ``F_o`` are all non-tension forces on a node (positive along the global axes). Gravity is
``-g e_z``.
"""
from __future__ import annotations

from .jit import FASTMATH as _FASTMATH, njit  # noqa: F401
from .layout import *  # noqa: F401,F403
from .rotations import (_chart_rotation, _cross, _inv3, body_rotation, euler_from_rotation,  # noqa: F401
                        euler_rates_to_omega, euler_rates_to_omega_series, omega_dot_to_euler_acc, rechart_body,
                        rotation_matrix)
from .cable_loads import current_at, node_assembly, node_reaction, segment_loads  # noqa: F401
from .body_dynamics import (_condense, _rotational_stiffness, _table_coefficients,  # noqa: F401
                            _translational_damping, aft_rotational_stiffness, aft_segment_stiffness, body_loads,
                            body_mass_blocks, condense_body, place_aft_nodes, table_lookup)
from .tension_solve import (_positions_from_tensions, assemble_tension_system, thesis_recursion_solve,  # noqa: F401
                            tree_ldlt_solve)
from .actuators import _compensator_node, _end_stop_force, _winch_speed  # noqa: F401
from .orbital_flow import _wave_flow, wave_orbital_velocity  # noqa: F401
from .houbolt import _quad3, _quad_interp, _step, advance, houbolt_step, houbolt_step_entry  # noqa: F401
