"""Layouts and codes the kernels share. First the column layout of the rigid-body parameter rows
``System.bp`` (one row per rigid body, float64): the only place the column numbers are written. Kernels
and builders index with these names (numba treats them as compile-time constants, so the compiled code is
the same as with bare numbers); a 3-vector starts at its name (``bp[b, BP_CG:BP_CG + 3]``, ``bp[b, BP_CG + 1]`` is its y component).

Body axes, tow point at the origin (docs/model-notes.md). Below: the solver-settings array, the step
counters, node kinds, status codes and the compensator/winch parameter and state arrays."""
import math


BP_MASS = 0                 # kg
BP_VOLUME = 1               # m^3 (buoyancy)
BP_AREA = 2                 # m^2, reference area of the coefficient tables
BP_LENGTH = 3               # m, reference length of the moment coefficients
BP_CG = 4                   # 4-6: centre of gravity r_G, m
BP_CB = 7                   # 7-9: centre of buoyancy r_B, m
BP_INERTIA = 10             # 10-12: principal moments of inertia about G, kg m^2
BP_ROT_DAMPING = 13         # 13-15: linear rotational damping coefficients
BP_QUAD_ROT_DAMPING = 16    # 16-18: quadratic rotational damping coefficients
BP_LIFT_SLOPE = 19          # lift-curve slope at zero incidence, per rad
BP_ADDED_MASS = 20          # 20-22: added mass (diagonal, at the tow point), kg
BP_ADDED_INERTIA = 23       # 23-25: added inertia (diagonal), kg m^2
BP_AFT_TOW_POINT = 26       # 26-28: aft tow point (series tows), m
BP_REDUCED_DOF = 29         # 1: surge/heave/pitch only (roll and yaw held), 0: 6 DOF
BP_TAIL_MASS = 30           # mass hanging from the aft tow point (series tows), kg
BP_ADDED_COUPLING = 31      # 31-66: the 6x6 added mass about the tow point, row-major over (surge, sway, heave,
                            #        roll, pitch, yaw), with its diagonal set to 0 (the diagonal is BP_ADDED_MASS
                            #        and BP_ADDED_INERTIA); all 0 for a diagonal added mass
BP_ADDED_COUPLED = 67       # 1: BP_ADDED_COUPLING has a non-zero entry, 0: diagonal added mass
BP_ADDED_CORIOLIS = 68      # 1: the added mass's Coriolis/centripetal terms (Munk moment included) are applied
BP_EXTERNAL_FORCE = 69      # 69-71: constant external force (thrusters), global axes, at the centre of gravity, N
BP_HAS_EXTERNAL = 72        # 1: BP_EXTERNAL_FORCE is not zero
BODY_PARAM = 73             # columns in a row


# ------------------------------------------------------------------------------------------------------
# solver settings array (SolverSettings.array(), float64): what the kernels read of the scene's [solver]
# ------------------------------------------------------------------------------------------------------
S_TOLERANCE = 0             # N, absolute tension change that ends Newton
S_RELATIVE_TOLERANCE = 1
S_MAX_ITERATIONS = 2
S_MAX_STRAIN = 3
S_ANGLE_TOLERANCE = 4       # rad
S_MAX_STEP_CUTS = 5
S_AS_PUBLISHED = 6          # 1: the thesis's tension recursion instead of the tree solve
S_RECHART_PITCH = 7         # rad (optional: shorter arrays use kernels.RECHART_PITCH)
S_PLANAR = 8                # 1: vertical-plane model (optional)
S_NEWTON_ESTIMATE = 9       # 1: newton_stop = "estimate" (optional)
S_PREDICTOR = 10            # 1: predictor = "adaptive" (optional; absent or 0: "quadratic")
S_BODY_REFRESH = 11         # steps a rigid body's load derivatives serve (solver.body_derivative_refresh;
                            # optional: absent or ≤ 1 recomputes them every step)
S_CABLE_REFRESH = 12        # steps the free nodes' Newton matrices serve (solver.cable_jacobian_refresh; optional:
                            # absent or ≤ 1 builds them at every iteration)
SETTINGS_SIZE = 13

# the Houbolt step's memory between steps (TimeLevels.pred_state, float64): the predictor's (solver.predictor =
# "adaptive"), the bodies' reused load derivatives' (solver.body_derivative_refresh > 1) and the free nodes' reused
# Newton matrices' (solver.cable_jacobian_refresh > 1)
PS_VALID = 0                # 1: the predictor's memory (TimeLevels.older_*) continues the time levels
PS_HIGHER = 1               # how many nodes, bodies and segments extrapolate one order higher in the next step
PS_BODY_VALID = 2           # 1: TimeLevels.body_relax / body_damp hold derivatives a step may reuse
PS_BODY_AGE = 3             # steps committed since they were computed (the computing step counts as 1)
PS_CABLE_VALID = 4          # 1: TimeLevels.node_matrix / node_inverse hold Newton matrices a step may reuse
PS_CABLE_AGE = 5            # steps committed since they were built (the building step counts as 1)
PS_CABLE_ITERATIONS = 6     # Newton iterations of the step that built them (a reusing step that needs more drops them)
PRED_STATE_SIZE = 7
#: Newton iterations beyond those of the step that built the kept node matrices after which a step reusing them gives
#: up (houbolt.advance retries it with fresh ones; measured: a reusing step in a sea otherwise ran to max_iterations,
#: 25, once in 400 steps, where the retry with fresh matrices took 4)
CABLE_REUSE_EXTRA_ITERATIONS = 3


# ------------------------------------------------------------------------------------------------------
# step counters (int64, Simulator.counters / KernelData.counters): what Simulator.stats reports
# ------------------------------------------------------------------------------------------------------
N_STEPS = 0                 # steps taken (sub-steps of cut steps included)
N_ITERATIONS = 1            # Newton iterations, summed
N_MAX_ITERATIONS = 2        # most iterations of one step
N_STEP_CUTS = 3             # step halvings
N_RECHARTS = 4              # body attitude re-charts
COUNTERS_SIZE = 5


# ------------------------------------------------------------------------------------------------------
# per-body diagonal estimates the Newton iteration relaxes the body-angle update with (HouboltWork.bkc, (nb, 9))
# ------------------------------------------------------------------------------------------------------
BK_STIFFNESS = 0            # 0-2: rotational stiffness about the body axes
BK_DAMPING = 3              # 3-5: rotational damping
BK_INERTIA = 6              # 6-8: rotational inertia (diagonal of the condensed A_rr)
BK_SIZE = 9

# ------------------------------------------------------------------------------------------------------
# node kinds, status codes of the step kernels, actuator parameter/state layouts
# ------------------------------------------------------------------------------------------------------
# status codes returned by the step kernels
OK = 0
FAIL_NEWTON = 1        # iteration cap reached / residual growing
FAIL_NAN = 2           # non-finite number appeared
FAIL_STRETCH = 3       # non-physical strain in a segment
FAIL_ANGLE = 4         # body pitch reached ±85° inside its attitude chart (guard: re-charting keeps it far below)

FREE = 0
PRESCRIBED_TOP = 1
PRESCRIBED_AFT = 2
PRESCRIBED_FIXED = 3   # anchor: fixed in space
COMPENSATOR = 4        # cable top node on a heave-compensator sheave: moves with the ship except along z
NEED_REMESH = 10       # advance(): not a failure — the winch line needs a node inserted/removed
RETRY_CONTACT = 11     # houbolt_step(): the sheave's end-stop contact state changed; redo the step

# moving attitude chart (see ``body_rotation``): a body whose local pitch exceeds this at the start of a
# step is re-charted (its local Euler angles restart from zero). Default of ``settings[S_RECHART_PITCH]``
# (``SolverSettings.rechart_pitch``) when the settings array is shorter.
RECHART_PITCH = math.pi / 6.0
# pitch (rad, ~85°) inside a body's attitude chart at which a step fails (FAIL_ANGLE): the Euler-angle
# singularity guard of every scheme
PITCH_LIMIT = 1.48
#: what the schemes without the moving attitude chart (explicit, generalized-α, Newmark) say when a body
#: reaches PITCH_LIMIT: a refusal of that attitude, not a numerical instability
NO_CHART_REFUSAL = ("body pitch reached ±85°, the limit of the plain Euler angles the {scheme} scheme integrates "
                    "(it has no moving attitude chart; solver.method = \"houbolt\" has one and takes bodies "
                    "through the vertical)")

# heave compensator parameter layout (float64[16])
C_MODE, C_K, C_B, C_MASS, C_PRELOAD, C_SMIN, C_SMAX, C_TRIAL, C_UNUSED, C_CMD, C_TAU, C_RATE, C_NODE, C_SHIP = range(14)
# compensator state layout (float64[8]): hits, in-contact flag, max penetration, actuator state
CS_HITS, CS_CONTACT, CS_PEN, CS_ACT = range(4)
COMP_PASSIVE, COMP_LOCKED, COMP_POSITION, COMP_FORCE = 1, 2, 3, 4
# winch parameter layout (float64[12]) and state (float64[4])
W_MODE, W_VCMD, W_VMAX, W_AMAX, W_LMIN, W_LMAX, W_TSET, W_GAIN, W_DEADBAND, W_SEG, W_LNOM = range(11)
WS_V, WS_LEN, WS_PAID = range(3)
WINCH_SPEED, WINCH_TENSION = 1, 2
# array sizes (the layouts above name fewer slots; the rest is spare)
COMP_SIZE, COMP_STATE_SIZE, WINCH_SIZE, WINCH_STATE_SIZE = 16, 8, 12, 4

__all__ = [n for n in dir() if n.isupper()]
