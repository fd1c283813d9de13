"""Column layout of the rigid-body parameter rows ``System.bp`` (one row per rigid body, float64): the only
place the column numbers are written. Kernels and builders index with these names (numba treats them as
compile-time constants, so the compiled code is the same as with bare numbers); a 3-vector starts at its
name (``bp[b, BP_CG:BP_CG + 3]``, ``bp[b, BP_CG + 1]`` is its y component).

Body axes, tow point at the origin (docs/model-notes.md)."""

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
BODY_PARAM = 31             # columns in a row


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
SETTINGS_SIZE = 10


# ------------------------------------------------------------------------------------------------------
# step counters (int64, Simulator.counters / KernelData.counters): what Simulator.stats reports
# ------------------------------------------------------------------------------------------------------
N_STEPS = 0                 # steps taken (sub-steps of cut steps included)
N_ITERATIONS = 1            # Newton iterations, summed
N_MAX_ITERATIONS = 2        # most iterations of one step
N_STEP_CUTS = 3             # step halvings
N_RECHARTS = 4              # body attitude re-charts
COUNTERS_SIZE = 5

__all__ = [n for n in dir() if n.startswith(("BP_", "S_", "N_"))] + ["BODY_PARAM", "SETTINGS_SIZE", "COUNTERS_SIZE"]
