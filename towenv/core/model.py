"""The typed model layer between the validated Scene and the compiled kernels.

:func:`towenv.core.system.build_system` turns a Scene into a :class:`~towenv.core.system.System` (flat
arrays); the named structures below are what the kernels receive, one per physical object or job:

* :class:`Topology` ......... which node each segment joins, junction adjacency, elimination order, bodies' nodes
* :class:`Segments` ......... per cable segment: unstretched length, diameter, mass, drag/added-mass coefficients, EA
* :class:`Bodies` ........... rigid towed bodies (parameter rows ``bp``, columns in :mod:`towenv.core.layout`,
  coefficient tables) and point bodies (per node)
* :class:`Water` ............ density, gravity, current profile
* :class:`WaveField` ........ wave components of the orbital-velocity option
* :class:`TimeLevels` ....... the dynamic state: three time levels of node positions and body angles, two of
  tensions, the top reaction, the compensator state, the bodies' attitude charts
* :class:`SavedStep` ........ the last good step (roll-back on divergence)
* :class:`Recording` ........ where the Houbolt ``advance`` writes records (``towenv.simulate``), or nothing
* :class:`HouboltWork` / :class:`ExplicitWork` ... the schemes' work arrays, each allocated by ``allocate``

They are ``typing.NamedTuple`` classes: numba compiles them as tuples (measured: no cost against the plain
tuples they replace), and a kernel reads a field by name (``topo.seg_lo``, ``work.flow``). The order of the
fields is an implementation detail: pass a structure whole, read it by name.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .layout import BK_SIZE

MAX_SEGS_PER_NODE = 8          # segments that may meet at one node (junctions)


class Topology(NamedTuple):
    seg_lo: np.ndarray          # int64 (ns,): lower node of each segment (away from the ship)
    seg_up: np.ndarray          # int64 (ns,): upper node (toward the ship)
    seg_uplocal: np.ndarray     # int64 (ns,): the segment's slot in its upper node's list
    node_kind: np.ndarray       # int64 (nn,): FREE, PRESCRIBED_TOP, PRESCRIBED_AFT, PRESCRIBED_FIXED, COMPENSATOR
    node_nseg: np.ndarray       # int64 (nn,): segments meeting at the node
    node_segs: np.ndarray       # int64 (nn, MAX_SEGS_PER_NODE): those segments (-1 = none)
    node_sgn: np.ndarray        # float64 (nn, MAX_SEGS_PER_NODE): +1 if the node is the segment's lower node
    order: np.ndarray           # int64: elimination order of the tension tree (leaves first)
    pos: np.ndarray             # int64: position of each node in ``order``
    body_node: np.ndarray       # int64 (nb,): tow-point node of each rigid body
    body_aft_node: np.ndarray   # int64 (nb,): aft tow-point node (series tows), -1 if none
    # the tension tree (system.tension_cliques): the lists above with each aft tow point merged into its body's
    # tow-point node (solver.series_coupling = "monolithic"; identical to them otherwise)
    tn_nseg: np.ndarray         # int64 (nn,)
    tn_segs: np.ndarray         # int64 (nn, MAX_SEGS_PER_NODE)
    tn_sgn: np.ndarray          # float64 (nn, MAX_SEGS_PER_NODE)
    tseg_up: np.ndarray         # int64 (ns,): upper node of each segment in the tension tree
    tseg_uplocal: np.ndarray    # int64 (ns,): its slot there


class Segments(NamedTuple):
    l0: np.ndarray              # m, unstretched length
    diam: np.ndarray            # m, hydrodynamic diameter
    mu: np.ndarray              # kg/m, mass per length
    cn: np.ndarray              # normal drag coefficient
    ct: np.ndarray              # tangential drag coefficient
    can: np.ndarray             # normal added-mass coefficient
    cat: np.ndarray             # tangential added-mass coefficient
    ea: np.ndarray              # N, axial stiffness (inf = inextensible)


class Bodies(NamedTuple):
    bp: np.ndarray              # float64 (nb, BODY_PARAM): rigid-body parameter rows (towenv.core.layout)
    btab_n: np.ndarray          # int64 (nb, 2): rows used in the vertical / horizontal coefficient tables
    btab: np.ndarray            # float64 (nb, 8, n): coefficient tables
    pb_mass: np.ndarray         # point bodies, per node: kg
    pb_vol: np.ndarray          # m^3
    pb_cda: np.ndarray          # m^2, drag area
    pb_ca: np.ndarray           # added-mass coefficient


class Water(NamedTuple):
    rho: float                  # kg/m^3
    g: float                    # m/s^2
    cur_z: np.ndarray           # m, depths of the current profile
    cur_v: np.ndarray           # m/s (n, 3), current at those depths


class WaveField(NamedTuple):
    amplitude: np.ndarray       # m
    omega: np.ndarray           # rad/s
    kx: np.ndarray              # 1/m, wavenumber components in the global frame
    ky: np.ndarray
    k: np.ndarray
    phase: np.ndarray           # rad
    options: np.ndarray         # [enabled (1.0 / 0.0), z_cut (m): below it every component has decayed]

    @staticmethod
    def off() -> "WaveField":
        return WaveField(np.zeros(1), np.ones(1), np.zeros(1), np.zeros(1), np.ones(1), np.zeros(1), np.zeros(2))


class TimeLevels(NamedTuple):
    hist_r: np.ndarray          # (3, nn, 3): node positions at t, t − Δt, t − 2Δt
    hist_ang: np.ndarray        # (3, nb, 3): body Euler angles (in each body's chart) at the same levels
    tens_hist: np.ndarray       # (2, ns): segment tensions at t, t − Δt
    top_react: np.ndarray       # (3,): force of the cable on its top node
    cstate: np.ndarray          # compensator state (kernels.CS_*)
    chart: np.ndarray           # (nb, 3, 3): each body's attitude chart
    # the predictor's memory (solver.predictor = "adaptive"; houbolt.predict / choose_predictor): the level before
    # the oldest above, and per node / body / segment whether the next step extrapolates one order higher (1.0)
    older_r: np.ndarray         # (nn, 3): node positions at t − 3Δt
    older_ang: np.ndarray       # (nb, 3): body Euler angles at t − 3Δt (in the charts above)
    older_tens: np.ndarray      # (ns,): segment tensions at t − 2Δt
    cubic_r: np.ndarray         # (nn,): 1.0: the node's position extrapolated cubically (else quadratically)
    cubic_ang: np.ndarray       # (nb,): 1.0: the body's angles extrapolated cubically (else quadratically)
    quad_tens: np.ndarray       # (ns,): 1.0: the segment's tension extrapolated quadratically (else linearly)
    pred_state: np.ndarray      # (PRED_STATE_SIZE,): memory valid, number of higher-order choices, body
    #                             derivatives valid and their age, node matrices valid and their age (layout.PS_*)
    # each rigid body's load derivatives kept for the next steps (solver.body_derivative_refresh > 1;
    # houbolt.iterate_coefficients): rate-only linearisations, never the converged solution
    body_relax: np.ndarray      # (nb, 6): rotational stiffness (3) and damping (3) of the loads (BK_STIFFNESS/BK_DAMPING
    #                             order, before the tail's stiffness is added)
    body_damp: np.ndarray       # (nb, 3, 3): translational damping −∂F/∂v (body axes)
    # each free node's Newton matrix M̃ = M + (11Δt/12) B + ½Δt² K_g and its inverse kept for the next steps
    # (solver.cable_jacobian_refresh > 1; houbolt.node_local_solve): the iteration's matrix, never its solution
    node_matrix: np.ndarray     # (nn, 3, 3)
    node_inverse: np.ndarray    # (nn, 3, 3)


class SavedStep(NamedTuple):
    hist_r: np.ndarray
    hist_ang: np.ndarray
    tens_hist: np.ndarray
    cstate: np.ndarray

    @staticmethod
    def allocate(nn: int, ns: int, nb: int) -> "SavedStep":
        return SavedStep(np.zeros((3, nn, 3)), np.zeros((3, nb, 3)), np.zeros((2, ns)), np.zeros(8))


class HouboltWork(NamedTuple):
    """Work arrays of the Houbolt step (contents are scratch between calls)."""
    tang: np.ndarray            # (ns, 3) unit tangents
    stretched: np.ndarray       # (ns,) stretched lengths
    drag: np.ndarray            # (ns, 2, 3) drag on each end of a segment
    bmat: np.ndarray            # (ns, 2, 3, 3) drag Jacobians
    madd: np.ndarray            # (ns, 3, 3) segment mass + added mass
    mnode: np.ndarray           # (nn, 3, 3) node mass matrices
    bnode: np.ndarray           # (nn, 3, 3) node damping (−∂F/∂v)
    fnode: np.ndarray           # (nn, 3) non-tension node forces
    acon: np.ndarray            # (nn, 3) node-local solve: constant part
    qvec: np.ndarray            # (nn, k, 3) node-local solve: tension influence vectors
    rs: np.ndarray              # (nn, 3) positions of the iterate
    vs: np.ndarray              # (nn, 3) velocities of the iterate
    kd: np.ndarray              # (ns,) tension-system diagonal
    kb: np.ndarray              # (nn, k, k) tension-system couplings at each node
    rhs: np.ndarray             # (ns,)
    dT: np.ndarray              # (ns,) tension update
    gres: np.ndarray            # (ns,) length residuals
    tens: np.ndarray            # (ns,) tensions of the iterate
    bX: np.ndarray              # (nb, 3, 3) body condensation: ω̇ = y − X a
    by: np.ndarray              # (nb, 3)
    blam: np.ndarray            # (nb, 3, 3) body rotation matrices
    angs: np.ndarray            # (nb, 3) Euler angles of the iterate
    dang: np.ndarray            # (nb, 3) Euler-angle rates
    omg: np.ndarray             # (nb, 3) body angular velocities
    hvec: np.ndarray            # (3,) scratch
    tmp3: np.ndarray            # (3,) scratch
    tmp33: np.ndarray           # (3, 3) scratch
    tmp33b: np.ndarray          # (3, 3) scratch
    att: np.ndarray             # (3, 3) body mass blocks / node-local matrix
    atr: np.ndarray             # (3, 3)
    arr: np.ndarray             # (3, 3)
    arrinv: np.ndarray          # (3, 3)
    cur_b: np.ndarray           # (3,) current at a body
    fb: np.ndarray              # (3,) body force
    mb: np.ndarray              # (3,) body moment
    bdiag: np.ndarray           # (1,) body damping diagonal
    react: np.ndarray           # (3,) node reaction
    bkc: np.ndarray             # (nb, BK_SIZE) body rotational stiffness, damping, inertia diagonals (layout.BK_*)
    bdmat: np.ndarray           # (nb, 3, 3) body translational damping
    scr: np.ndarray             # (6, 3) scratch
    flow: np.ndarray            # (nn, 3) wave orbital velocity at the nodes
    recursion: np.ndarray       # (6, ns) scratch of the as-published tension recursion
    gaft: np.ndarray            # (nb, 3, 3) monolithic series coupling: ω̇ += G f for a global force f at the aft point
    haft: np.ndarray            # (nb, 3, 3) ... and the tow-point node's force += H f (body_dynamics.aft_transfer)
    qaft: np.ndarray            # (nb, k, 3) ... ∂r_aft/∂T of the tow-point node's tension-tree list (rotation included)
    top_sub: np.ndarray         # (3,) the tow point of a sub-step (houbolt.advance's step cuts)
    flow_v: np.ndarray          # (3,) scratch of the orbital-velocity evaluation (orbital_flow._wave_flow)
    no_bmat: np.ndarray         # (0, 2, 3, 3): an empty bmat — drag Jacobians not wanted (cable_loads.segment_loads)

    @staticmethod
    def allocate(nn: int, ns: int, nb: int) -> "HouboltWork":
        z, mk, nb1 = np.zeros, MAX_SEGS_PER_NODE, max(nb, 1)
        return HouboltWork(
            z((ns, 3)), z(ns), z((ns, 2, 3)), z((ns, 2, 3, 3)), z((ns, 3, 3)),
            z((nn, 3, 3)), z((nn, 3, 3)), z((nn, 3)), z((nn, 3)), z((nn, mk, 3)), z((nn, 3)), z((nn, 3)),
            z(ns), z((nn, mk, mk)), z(ns), z(ns), z(ns), z(ns),
            z((nb, 3, 3)), z((nb, 3)), z((nb, 3, 3)), z((nb, 3)), z((nb, 3)), z((nb, 3)),
            z(3), z(3), z((3, 3)), z((3, 3)), z((3, 3)), z((3, 3)), z((3, 3)), z((3, 3)),
            z(3), z(3), z(3), z(1), z(3), z((nb1, BK_SIZE)), z((nb1, 3, 3)), z((6, 3)), z((nn, 3)), z((6, ns)),
            z((nb1, 3, 3)), z((nb1, 3, 3)), z((nb1, mk, 3)), z(3), z(3), z((0, 2, 3, 3)))


class Recording(NamedTuple):
    """Where :func:`towenv.core.houbolt.advance` writes a record every ``plan[0]`` steps (``towenv.simulate``'s
    compiled recording, :mod:`towenv.core.recording`); ``plan[0] == 0``: no recording (:meth:`none`).
    ``plan = [steps per record, row of the first record, step count at the call's start]``. After record j
    (0-based) of the call: ``R[row]`` node positions, ``RB[row]`` the body nodes' three time levels, ``A[row]``
    body angles, ``C[row]`` attitude charts, ``T[row]`` tensions, ``F[row]`` top reaction (row = plan[1] + j);
    ``CZ[j]`` the sheave and ship heights (three levels), ``CKB[j]`` the compensator's k, b (empty without
    one)."""
    plan: np.ndarray            # int64 (3,)
    bnodes: np.ndarray          # int64 (nbn,) body nodes
    cnodes: np.ndarray          # int64 (2,) sheave node, ship (top) node
    R: np.ndarray               # (n, nn, 3)
    RB: np.ndarray              # (n, 3, nbn, 3)
    A: np.ndarray               # (n, 3, nb, 3)
    C: np.ndarray               # (n, nb, 3, 3)
    T: np.ndarray               # (n, ns)
    F: np.ndarray               # (n, 3)
    CZ: np.ndarray              # (m, 3, 2)
    CKB: np.ndarray             # (m, 2)

    @staticmethod
    def none() -> "Recording":
        """No recording (the arrays are empty; same types as a real one, so ``advance`` compiles once)."""
        i, z = np.zeros, np.zeros
        return Recording(i(3, np.int64), i(0, np.int64), i(2, np.int64), z((0, 0, 3)), z((0, 3, 0, 3)),
                         z((0, 3, 0, 3)), z((0, 0, 3, 3)), z((0, 0)), z((0, 3)), z((0, 3, 2)), z((0, 2)))


#: ``advance(..., rec=NO_RECORDING)``: no records (shared; its arrays are empty and never written)
NO_RECORDING = Recording.none()


class ExplicitWork(NamedTuple):
    """Work arrays of the load evaluation of the explicit and α schemes (``explicit._rates``)."""
    tang: np.ndarray
    stretched: np.ndarray
    drag: np.ndarray
    bmat: np.ndarray
    madd: np.ndarray
    mnode: np.ndarray
    bnode: np.ndarray
    fnode: np.ndarray
    lam: np.ndarray             # (3, 3) body rotation
    tmp3: np.ndarray
    fb: np.ndarray
    mb: np.ndarray
    att: np.ndarray
    atr: np.ndarray
    arr: np.ndarray
    arrinv: np.ndarray
    hvec: np.ndarray
    aeff: np.ndarray            # (3, 3)
    bX: np.ndarray              # (nb, 3, 3)
    by: np.ndarray              # (nb, 3)
    react: np.ndarray
    cur_b: np.ndarray
    minv: np.ndarray            # (3, 3)
    bdiag: np.ndarray
    wbody: np.ndarray           # (3,)

    @staticmethod
    def allocate(nn: int, ns: int, nb: int) -> "ExplicitWork":
        z, nb1 = np.zeros, max(nb, 1)
        return ExplicitWork(
            z((ns, 3)), z(ns), z((ns, 2, 3)), z((ns, 2, 3, 3)), z((ns, 3, 3)), z((nn, 3, 3)), z((nn, 3, 3)),
            z((nn, 3)), z((3, 3)), z(3), z(3), z(3), z((3, 3)), z((3, 3)), z((3, 3)), z((3, 3)), z(3),
            z((3, 3)), z((nb1, 3, 3)), z((nb1, 3)), z(3), z(3), z((3, 3)), z(1), z(3))


class AlphaState(NamedTuple):
    """State of the generalized-α / Newmark schemes (explicit second-order form)."""
    r: np.ndarray               # (nn, 3) node positions
    v: np.ndarray               # (nn, 3) velocities
    acc: np.ndarray             # (nn, 3) α-weighted accelerations
    fpr: np.ndarray             # (nn, 3) M⁻¹F at the state
    ang: np.ndarray             # (nb, 3) body Euler angles
    dang: np.ndarray            # (nb, 3) their rates
    aacc: np.ndarray            # (nb, 3) α-weighted angle accelerations
    afpr: np.ndarray            # (nb, 3) angle accelerations from the loads at the state

    @staticmethod
    def allocate(nn: int, nb: int) -> "AlphaState":
        z = np.zeros
        return AlphaState(z((nn, 3)), z((nn, 3)), z((nn, 3)), z((nn, 3)), z((nb, 3)), z((nb, 3)), z((nb, 3)),
                          z((nb, 3)))


class AlphaTrial(NamedTuple):
    """Trial state of one α step and the loads evaluated at it."""
    r1: np.ndarray              # (nn, 3)
    v1: np.ndarray              # (nn, 3)
    acc1: np.ndarray            # (nn, 3)
    ang1: np.ndarray            # (nb, 3)
    dang1: np.ndarray           # (nb, 3)
    omg1: np.ndarray            # (nb, 3) body angular velocities
    aacc1: np.ndarray           # (nb, 3)
    out_a: np.ndarray           # (nn, 3) node accelerations from the loads
    out_dang: np.ndarray        # (nb, 3)
    out_domg: np.ndarray        # (nb, 3) body angular accelerations
    qdd: np.ndarray             # (nb, 3) Euler-angle accelerations from the loads
    tens: np.ndarray            # (ns,) tensions

    @staticmethod
    def allocate(nn: int, ns: int, nb: int) -> "AlphaTrial":
        z = np.zeros
        return AlphaTrial(z((nn, 3)), z((nn, 3)), z((nn, 3)), z((nb, 3)), z((nb, 3)), z((nb, 3)), z((nb, 3)),
                          z((nn, 3)), z((nb, 3)), z((nb, 3)), z((nb, 3)), z(ns))


__all__ = ["AlphaState", "AlphaTrial", "Topology", "Segments", "Bodies", "Water", "WaveField", "TimeLevels", "SavedStep", "HouboltWork",
           "Recording", "NO_RECORDING",
           "ExplicitWork", "MAX_SEGS_PER_NODE"]
