"""The stepping interface of the simulator core: ``Simulator`` (reset / advance / snapshot / restore)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NamedTuple

import numpy as np
from . import layout as L
from .layout import BP_AFT_TOW_POINT, BP_CB, BP_CG, BP_REDUCED_DOF

from ..errors import SimulationDivergence
from . import kernels as K
from .excitation import TowPointPath
from .statics import quasi_static
from .model import HouboltWork, SavedStep, TimeLevels, WaveField
from .schemes import make_scheme
from .system import System, build_system

_CAUSES = {
    K.FAIL_NEWTON: "Newton iteration on the segment tensions did not converge (after step cuts)",
    K.FAIL_NAN: "a non-finite number appeared",
    K.FAIL_STRETCH: "non-physical stretch: strain above solver.max_strain",
    K.FAIL_ANGLE: "body pitch reached ±85° inside its attitude chart (re-charting could not keep up)",
}


from ..scene import scene_field as _get  # noqa: E402  (the one scene accessor; defaults are the schema's)


@dataclass
class Snapshot:
    """A copy of the full dynamic state. Restoring one is a few array copies (microseconds); after a
    winch node insertion/removal it also re-installs the discretisation of that time."""
    hist_r: np.ndarray
    hist_ang: np.ndarray
    tens_hist: np.ndarray
    top_react: np.ndarray
    step: int
    cstate: np.ndarray
    wstate: np.ndarray
    comp: np.ndarray
    winch: np.ndarray
    system: object = None
    l0: np.ndarray | None = None
    chart: np.ndarray | None = None     # per-body attitude chart (None: identity, snapshots of older code)
    # the Houbolt step's memory (Simulator.older: predictor, reused body derivatives; None: forgotten)
    predictor: tuple | None = None


def _scene_default(name):
    from ..scene import Solver
    return Solver.model_fields[name].default


@dataclass
class SolverSettings:
    """The solver settings the kernels read. Every default is the scene schema's (``towenv.scene.Solver``, the
    one source), except ``rechart_pitch``, which is not a scene field."""
    dt: float = _scene_default("dt")
    tolerance: float = _scene_default("tolerance")
    relative_tolerance: float = _scene_default("relative_tolerance")
    max_iterations: int = _scene_default("max_iterations")
    max_step_cuts: int = _scene_default("max_step_cuts")
    max_strain: float = _scene_default("max_strain")
    settle_time: float = _scene_default("settle_time")
    angle_tolerance: float = _scene_default("angle_tolerance")
    tension_solve: str = _scene_default("tension_solve")
    # moving attitude chart: a body whose pitch in its chart exceeds this (rad) is re-charted before the
    # next step (docs/model-notes.md "Body attitude"); 0 re-charts every step (most accurate, not
    # bit-identical to the plain Euler-angle runs). Not a scene field: set it on ``Simulator.settings``.
    rechart_pitch: float = K.RECHART_PITCH
    planar: bool = _scene_default("planar")
    newton_stop: str = _scene_default("newton_stop")
    predictor: str = _scene_default("predictor")
    body_derivative_refresh: int = _scene_default("body_derivative_refresh")
    cable_jacobian_refresh: int = _scene_default("cable_jacobian_refresh")

    def array(self):
        if not (0.0 <= self.rechart_pitch <= 1.2):
            raise ValueError(f"rechart_pitch: must be within [0, 1.2] rad (got {self.rechart_pitch!r})")
        if self.newton_stop not in ("change", "estimate"):
            raise ValueError(f"solver.newton_stop: must be 'change' or 'estimate' (got {self.newton_stop!r})")
        if self.predictor not in ("adaptive", "quadratic"):
            raise ValueError(f"solver.predictor: must be 'adaptive' or 'quadratic' (got {self.predictor!r})")
        if not (isinstance(self.body_derivative_refresh, (int, np.integer)) and not isinstance(
                self.body_derivative_refresh, bool) and 1 <= self.body_derivative_refresh <= 1000):
            raise ValueError("solver.body_derivative_refresh: must be an integer within [1, 1000] "
                             f"(got {self.body_derivative_refresh!r})")
        if not (isinstance(self.cable_jacobian_refresh, (int, np.integer)) and not isinstance(
                self.cable_jacobian_refresh, bool) and 1 <= self.cable_jacobian_refresh <= 1000):
            raise ValueError("solver.cable_jacobian_refresh: must be an integer within [1, 1000] "
                             f"(got {self.cable_jacobian_refresh!r})")
        a = np.empty(L.SETTINGS_SIZE)
        a[L.S_TOLERANCE] = self.tolerance
        a[L.S_RELATIVE_TOLERANCE] = self.relative_tolerance
        a[L.S_MAX_ITERATIONS] = self.max_iterations
        a[L.S_MAX_STRAIN] = self.max_strain
        a[L.S_ANGLE_TOLERANCE] = self.angle_tolerance
        a[L.S_MAX_STEP_CUTS] = self.max_step_cuts
        a[L.S_AS_PUBLISHED] = 1.0 if self.tension_solve == "as_published" else 0.0
        a[L.S_RECHART_PITCH] = self.rechart_pitch
        a[L.S_PLANAR] = 1.0 if self.planar else 0.0
        a[L.S_NEWTON_ESTIMATE] = 1.0 if self.newton_stop == "estimate" else 0.0
        a[L.S_PREDICTOR] = 1.0 if self.predictor == "adaptive" else 0.0
        a[L.S_BODY_REFRESH] = float(self.body_derivative_refresh)
        a[L.S_CABLE_REFRESH] = float(self.cable_jacobian_refresh)
        return a


class KernelData(NamedTuple):
    """What :func:`towenv.core.kernels.advance` works on for one Simulator, by reference (not copies):
    ``Simulator.kernel_data()``. A caller that runs the kernel itself (the environments' batched stepper,
    the recorder) calls ``kernels.advance(n, dt, tops, *kd.head, t0, kd.wave, model.NO_RECORDING)``; on ``NEED_REMESH`` it calls
    ``kd.remesh()`` and fetches ``kernel_data()`` again (the arrays are new); on a failure status
    ``kd.divergence(status, element, max_change, t_fail)`` is the exception ``advance_steps`` would raise.
    It must keep ``step_count`` itself. The tuples' layouts are the kernel's, not an API: pass them whole."""
    args: tuple             # (top_node, topology, segment, body and environment parameters): the discretisation
    settings: np.ndarray    # SolverSettings.array()
    state: tuple            # the dynamic state (position/angle histories, tensions, top reaction, actuators, charts)
    work: tuple             # work arrays
    saved: tuple            # the last good step (roll-back)
    counters: np.ndarray    # steps, iterations, max iterations, step cuts, re-charts
    comp: np.ndarray        # compensator parameters (commands are written here)
    winch: np.ndarray       # winch parameters (commands are written here)
    wstate: np.ndarray      # winch state
    wave: tuple             # wave components of the orbital-velocity option
    remesh: Callable[[], None]
    divergence: Callable[..., SimulationDivergence]

    @property
    def head(self) -> tuple:
        """The arguments of ``kernels.advance`` between ``tops`` and ``t0``."""
        return tuple(self.args) + (self.settings, self.state, self.work, self.saved, self.counters, self.comp,
                                   self.winch, self.wstate)


def load(scene, overrides=None):
    """Resolve a scene given as a path, a dict, an embedded scene name or a Scene."""
    from ..scene import load_scene
    sc = load_scene(scene)
    if overrides:
        sc = sc.with_overrides(**overrides)
    return sc


class Simulator:
    """Lumped-mass tow simulator for one scene.

    >>> sim = Simulator("two_part_tow_1")
    >>> sim.advance(10.0)          # seconds
    >>> sim.body_state("fish")["position"]
    """

    def __init__(self, scene, **overrides):
        short = {k: v for k, v in overrides.items() if k in SolverSettings.__dataclass_fields__}
        dotted = {k: v for k, v in overrides.items() if k not in short}
        dotted.update({f"solver.{k}": v for k, v in short.items()})
        self.scene = load(scene, dotted)
        self.system: System = build_system(self.scene)
        solver = _get(self.scene, "solver")
        self.settings = SolverSettings(**{k: _get(solver, k, getattr(SolverSettings, k))
                                          for k in SolverSettings.__dataclass_fields__
                                          if _get(solver, k) is not None})
        base = getattr(self.scene, "source_dir", None)
        data_dir = Path(__file__).resolve().parent.parent / "scenes" / "data"
        self.path = TowPointPath(_get(self.scene, "vessel"), Path(base) if base else None, data_dir)
        self.wave = None
        self.vessel_motion = self._vessel_motion(Path(base) if base else None, data_dir)
        if self.vessel_motion is not None:
            self.path.oscillations.append(self.vessel_motion)
        if self.settings.tension_solve == "as_published" and (
                np.any(self.system.node_nseg > 2) or self.system.n_rigid + len(self.system.bodies) > 1):
            raise ValueError("solver.tension_solve: 'as_published' (the thesis recursion) handles a single chain "
                             "only (no junctions or series bodies)")
        self._check_reduced_models()
        self.comp = np.zeros(K.COMP_SIZE)
        self.winch = np.zeros(K.WINCH_SIZE)
        self.wstate = np.zeros(K.WINCH_STATE_SIZE)
        self.cstate = np.zeros(K.COMP_STATE_SIZE)
        self._allocate()
        self._setup_actuators()
        #: the time scheme solver.method names (towenv.core.schemes): it advances this simulator
        self.scheme = make_scheme(self)
        self._initial_state()
        self.scheme.start()
        self._initial = self.snapshot()

    def _check_reduced_models(self):
        """``solver.planar`` (vertical-plane model) and bodies with ``dof = "surge_heave_pitch"``: refuse what
        they cannot represent, naming the field; ``solver.newton_stop = "estimate"`` is refused for the other
        solvers."""
        sc = self.scene
        if self.settings.newton_stop != "change":
            method = _get(_get(sc, "solver"), "method", "houbolt")
            if method != "houbolt":
                raise ValueError(f"solver.newton_stop: 'estimate' exists for the houbolt solver only (solver.method = "
                                 f"{method!r}); use 'change'")
        reduced = [b.name for b in self.system.bodies if getattr(b, "rigid_index", -1) >= 0
                   and self.system.bp[b.rigid_index, BP_REDUCED_DOF] != 0.0]
        if not self.settings.planar and not reduced:
            return
        what = "solver.planar" if self.settings.planar else f"bodies {reduced!r}: dof = 'surge_heave_pitch'"
        method = _get(_get(sc, "solver"), "method", "houbolt")
        if method != "houbolt":
            raise ValueError(f"{what}: the reduced models exist for the houbolt solver only (solver.method = "
                             f"{method!r})")
        if not self.settings.planar:
            return

        def refuse(field, why):
            raise ValueError(f"{field}: {why} — the vertical-plane model (solver.planar = true) needs a scene "
                             f"without lateral excitation; use the 3-D model (solver.planar = false)")
        s = self.system
        if np.any(s.cur_v[:, 1] != 0.0):
            refuse("current", f"the lateral (y) current component must be 0 (got {s.cur_v[:, 1].tolist()} m/s)")
        vessel = _get(sc, "vessel")
        if vessel is not None:
            if float(_get(vessel, "heading_deg", 0.0) or 0.0) != 0.0:
                refuse("vessel.heading_deg", f"must be 0 (the plane is the global x–z plane; got "
                                             f"{_get(vessel, 'heading_deg')!r})")
            from ..scene import TurnManoeuvre
            for i, m in enumerate(_get(vessel, "manoeuvres", ()) or ()):
                if isinstance(m, TurnManoeuvre):
                    refuse(f"vessel.manoeuvres[{i}]", "a turn is lateral motion")
            for i, e in enumerate(_get(vessel, "excitation", ()) or ()):
                if _get(e, "axis", None) == "y":
                    refuse(f"vessel.excitation[{i}].axis", "sway excitation ('y') is lateral motion")
        sea = _get(sc, "sea")
        if sea is not None:
            if float(_get(sea, "heading_deg", 180.0)) % 180.0 != 0.0:
                refuse("sea.heading_deg", f"must be 180 (head seas) or 0 (following seas) (got "
                                          f"{_get(sea, 'heading_deg')!r})")
            if _get(sea, "spreading_s") is not None:
                refuse("sea.spreading_s", "a short-crested sea excites sway, roll and yaw")
        for bm in s.bodies:
            if bm.rigid_index < 0:
                continue
            p = s.bp[bm.rigid_index]
            for name, k in (("cg", BP_CG + 1), ("cb", BP_CB + 1), ("aft_tow_point", BP_AFT_TOW_POINT + 1)):   # y components
                if p[k] != 0.0:
                    refuse(f"bodies[{bm.name!r}].{name}", f"the lateral (y) offset must be 0 (got {p[k]!r} m)")
            nh = int(s.btab_n[bm.rigid_index, 1])
            tab = s.btab[bm.rigid_index]
            cy0 = K.table_lookup(0.0, tab[4], tab[6], nh)
            cn0 = K.table_lookup(0.0, tab[4], tab[7], nh)
            if abs(cy0) > 1e-12 or abs(cn0) > 1e-12:
                refuse(f"bodies[{bm.name!r}].horizontal_coefficients",
                       f"side force and yaw moment at zero sideslip must be 0 (got {cy0!r}, {cn0!r})")
        y0 = None
        for node, pos in s.anchors.items():
            y0 = self.path.position(np.array([0.0]))[0][1] if y0 is None else y0
            if pos[1] != y0:
                refuse("lines (anchor)", f"an anchor off the plane y = {y0!r} m (got y = {pos[1]!r} m)")

    _NO_WAVE = WaveField.off()

    def _wave_arrays(self):
        """Wave components for the orbital-velocity option ([sea] orbital_velocities = true)."""
        sea = _get(self.scene, "sea")
        if self.wave is None or sea is None or not getattr(sea, "orbital_velocities", False):
            return self._NO_WAVE
        w = self.wave
        if getattr(self, "_wave_cache", (None,))[0] is not w:
            off = self.path.initial_heading
            kx = w.k * np.cos(w.direction + off)
            ky = w.k * np.sin(w.direction + off)
            vmax = float(np.sum(w.amplitude * w.omega))
            z_cut = np.log(1e-6 / vmax) / float(np.min(w.k)) if vmax > 1e-6 else 0.0
            self._wave_cache = (w, WaveField(w.amplitude.copy(), w.omega.copy(), kx, ky, w.k.copy(), w.phase.copy(),
                                             np.array([1.0, z_cut])))
        return self._wave_cache[1]

    def set_sea(self, sea=None, seed: int = 0, n_components: int | None = None):
        """Replace the sea (a ``towenv.sea.SeaState``, a scene ``[sea]`` table/dict, or None for calm) and
        its random seed, keeping the vessel model. The initial state is unchanged (it is the steady tow),
        so ``reset()`` after ``set_sea`` starts a new episode in the new sea in microseconds."""
        from .. import vessel as V
        from ..sea import SeaState, synthesize
        if self.vessel_motion is not None and self.vessel_motion in self.path.oscillations:
            self.path.oscillations.remove(self.vessel_motion)
        self.__dict__.pop("_top_blocks", None)
        vessel = _get(self.scene, "vessel")
        src = None
        if vessel is not None and not isinstance(vessel, dict):
            src = vessel.model
            if vessel.rao_file is not None and self.vessel_motion is not None:
                src = self.vessel_motion.source
        if sea is None:
            self.wave, self.vessel_motion = None, None
            return
        if src is None:
            raise ValueError("set_sea: the scene has no vessel model (vessel.model or vessel.rao_file)")
        if isinstance(sea, dict):
            from ..scene import Sea
            sea = Sea(**sea).sea_state()
        elif not isinstance(sea, SeaState):
            sea = sea.sea_state()
        ncomp = n_components or getattr(_get(self.scene, "sea"), "n_components", 200) or 200
        self.wave = synthesize(sea, duration=3600.0, seed=seed, n_components=ncomp)
        lever = None if vessel.lever_arm is None else np.asarray(vessel.lever_arm, float)
        self.vessel_motion = V.TowPointMotion.from_path(self.path, src, self.wave, lever)
        self.path.oscillations.append(self.vessel_motion)

    def _vessel_motion(self, base, data_dir):
        """Wave-induced tow-point motion from the [sea] and the vessel model / RAO table / record."""
        vessel = _get(self.scene, "vessel")
        if vessel is None or isinstance(vessel, dict):
            return None
        src = None

        def resolve(f):
            p = Path(f)
            if p.is_absolute():
                return p
            for d in (base, data_dir, Path.cwd()):
                if d is not None and (d / p).exists():
                    return d / p
            return p

        from .. import vessel as V
        if vessel.motion_file is not None:
            src = V.MotionRecord.from_csv(resolve(vessel.motion_file))
        elif vessel.rao_file is not None:
            src = V.RAOTable.from_csv(resolve(vessel.rao_file))
        elif vessel.model is not None:
            src = vessel.model
        if src is None:
            return None
        sea = _get(self.scene, "sea")
        if sea is not None and not isinstance(src, V.MotionRecord):
            from ..sea import synthesize
            self.wave = synthesize(sea.sea_state(), duration=3600.0, seed=sea.seed, n_components=sea.n_components)
        lever = None if vessel.lever_arm is None else np.asarray(vessel.lever_arm, float)
        return V.TowPointMotion.from_path(self.path, src, self.wave, lever)

    # ------------------------------------------------------------------------------------------
    def _allocate(self):
        s = self.system
        nn, ns, nb = s.n_nodes, s.n_segments, s.n_rigid
        self.hist_r = np.zeros((3, nn, 3))
        self.hist_ang = np.zeros((3, nb, 3))
        self.body_chart = np.tile(np.eye(3), (nb, 1, 1))
        self.tens_hist = np.zeros((2, ns))
        self.top_react = np.zeros(3)
        self._older = (np.zeros((nn, 3)), np.zeros((nb, 3)), np.zeros(ns), np.zeros(nn), np.zeros(nb), np.zeros(ns),
                       np.zeros(L.PRED_STATE_SIZE), np.zeros((nb, 6)), np.zeros((nb, 3, 3)), np.zeros((nn, 3, 3)),
                       np.zeros((nn, 3, 3)))
        self._state = TimeLevels(self.hist_r, self.hist_ang, self.tens_hist, self.top_react, self.cstate,
                                 self.body_chart, *self._older)
        self._ws = HouboltWork.allocate(nn, ns, nb)
        self._saved = SavedStep.allocate(nn, ns, nb)
        if not hasattr(self, "counters"):
            self.counters = np.zeros(L.COUNTERS_SIZE, np.int64)    # layout: towenv.core.layout N_*
        self._args = (s.top_node, s.topo(), s.segp(), s.bodyp(), s.env())

    _COMP_MODES = {"passive": K.COMP_PASSIVE, "locked": K.COMP_LOCKED, "position": K.COMP_POSITION,
                   "force": K.COMP_FORCE}
    _WINCH_MODES = {"speed": K.WINCH_SPEED, "constant_tension": K.WINCH_TENSION}

    def _setup_actuators(self):
        s = self.system
        c = _get(self.scene, "compensator")
        if c is not None:
            p = self.comp
            p[K.C_MODE] = self._COMP_MODES[c.mode]
            p[K.C_K] = c.stiffness
            p[K.C_B] = c.damping
            p[K.C_MASS] = c.mass
            p[K.C_SMIN] = -0.5 * c.stroke
            p[K.C_SMAX] = 0.5 * c.stroke
            p[K.C_TAU] = c.actuator_time_constant
            p[K.C_RATE] = c.rate_limit
            p[K.C_NODE] = s.comp_node
            p[K.C_SHIP] = s.top_node
            self._comp_bounds = (tuple(c.stiffness_bounds), tuple(c.damping_bounds))
        w = _get(self.scene, "winch")
        if w is not None:
            roots = [ln.name for ln in self.scene.lines if ln.top_kind == "vessel"]
            self.winch_line = w.line or roots[0]
            lm = s.line(self.winch_line)
            ln = self.scene.line(self.winch_line)
            l_nom = w.nominal_segment_length or float(s.l0[lm.segments[0]])
            junctions = self.scene.junctions(self.winch_line) if hasattr(self.scene, "junctions") else []
            below = (ln.length - min(junctions)) if junctions else 0.0
            p = self.winch
            p[K.W_MODE] = self._WINCH_MODES[w.mode]
            p[K.W_VCMD] = w.speed
            p[K.W_VMAX] = w.max_speed
            p[K.W_AMAX] = w.max_acceleration
            p[K.W_LMIN] = w.min_length if w.min_length is not None else below + l_nom
            p[K.W_LMAX] = w.max_length if w.max_length is not None else 10.0 * ln.length
            p[K.W_TSET] = w.set_tension
            p[K.W_GAIN] = w.gain
            p[K.W_DEADBAND] = w.deadband
            p[K.W_SEG] = lm.segments[0]
            p[K.W_LNOM] = l_nom
            self.wstate[K.WS_LEN] = float(s.l0[lm.segments].sum())

    def _initial_state(self):
        s = self.system
        dt = self.settings.dt
        U = self.path.initial_velocity()
        x0 = self.path.position(np.array([0.0]))[0]
        r0, T0, ang0 = quasi_static(s, x0, U)
        self.static_positions, self.static_tensions, self.static_angles = r0.copy(), T0.copy(), ang0.copy()
        for k in range(3):
            self.hist_r[k] = r0 - k * dt * U
            self.hist_ang[k] = ang0
        self.tens_hist[:] = T0
        self.forget_step_memory()
        self.step_count = 0
        settle = float(self.settings.settle_time or 0.0)
        if settle > 0:
            n = int(round(settle / dt))
            block = 65536              # tow-point positions are built per block: memory stays bounded
            for b in range(0, n, block):
                tops = x0 + np.outer(dt * np.arange(b + 1, min(n, b + block) + 1), U)
                self._run(tops, dt, t_start=-settle + b * dt)
            shift = n * dt * U
            self.hist_r -= shift
            self.step_count = 0
        else:
            self._static_reaction(U)
        if self.comp[K.C_MODE] > 0:
            # preload: the compensator carries the static cable force at mid-stroke
            self.comp[K.C_PRELOAD] = -self.top_react[2]
        self.counters[:] = 0

    def _static_reaction(self, U):
        """Tow-point reaction of the (steady) initial state, before any step was taken."""
        s = self.system
        ws = self._ws
        r = self.hist_r[0]
        v = np.tile(U, (s.n_nodes, 1))
        tang, stretched, drag, bmat, madd, mnode, bnode, fnode = (ws.tang, ws.stretched, ws.drag, ws.bmat, ws.madd,
                                                                  ws.mnode, ws.bnode, ws.fnode)
        K.segment_loads(r, v, s.seg_lo, s.seg_up, s.l0, s.diam, s.mu, s.cn, s.ct, s.can, s.cat, s.rho, s.g,
                        s.cur_z, s.cur_v, tang, stretched, drag, bmat, madd)
        K.node_assembly(r, v, s.node_kind, s.node_nseg, s.node_segs, s.node_sgn, s.l0, s.diam, s.mu, s.rho, s.g, drag, bmat,
                        madd, s.pb_mass, s.pb_vol, s.pb_cda, s.pb_ca, s.cur_z, s.cur_v, mnode, bnode, fnode)
        K.node_reaction(s.cable_top_node, r, r, r, r, self.settings.dt, s.node_nseg, s.node_segs, s.node_sgn,
                        tang, self.tens_hist[0], mnode, fnode, self.top_react)

    # ------------------------------------------------------------------------------------------
    @property
    def dt(self) -> float:
        return self.settings.dt

    @property
    def t(self) -> float:
        return self.step_count * self.settings.dt

    def snapshot(self) -> Snapshot:
        winch = self.winch[K.W_MODE] > 0
        snap = Snapshot(self.hist_r.copy(), self.hist_ang.copy(), self.tens_hist.copy(), self.top_react.copy(),
                        self.step_count, self.cstate.copy(), self.wstate.copy(), self.comp.copy(), self.winch.copy(),
                        self.system if winch else None, self.system.l0.copy() if winch else None,
                        self.body_chart.copy(), tuple(a.copy() for a in self._older))
        self.scheme.snapshot(snap)
        return snap

    @property
    def older(self) -> tuple:
        """The Houbolt step's memory between steps, by reference: ``model.TimeLevels``' last nine arrays — the
        predictor's (older_r, older_ang, older_tens, cubic_r, cubic_ang, quad_tens; solver.predictor), pred_state
        (layout.PS_*), the bodies' reused load derivatives (body_relax, body_damp;
        solver.body_derivative_refresh) and the free nodes' reused Newton matrices (node_matrix, node_inverse;
        solver.cable_jacobian_refresh) — docs/architecture.md."""
        return self._older

    def forget_step_memory(self) -> None:
        """The Houbolt step's memory no longer continues the time levels (they were written from outside the
        step: initial state, remesh, restore of an older snapshot, another scheme): the next steps extrapolate
        with the lower orders until a step has been committed on top of them, and the next step computes the
        bodies' load derivatives and the free nodes' Newton matrices afresh."""
        self._older[6][L.PS_VALID] = 0.0
        self._older[6][L.PS_BODY_VALID] = 0.0
        self._older[6][L.PS_CABLE_VALID] = 0.0

    def restore(self, snap: Snapshot) -> None:
        if snap.system is not None and snap.system is not self.system:
            self.system = snap.system
            self._allocate()
        if snap.l0 is not None:
            self.system.l0[...] = snap.l0
        self.hist_r[...] = snap.hist_r
        self.hist_ang[...] = snap.hist_ang
        if snap.chart is not None:
            self.body_chart[...] = snap.chart
        else:
            self.body_chart[...] = np.eye(3)
        self.tens_hist[...] = snap.tens_hist
        if snap.predictor is not None and len(snap.predictor) == len(self._older) and all(
                a.shape == b.shape for a, b in zip(snap.predictor, self._older)):
            for a, b in zip(self._older, snap.predictor):
                a[...] = b
        else:
            self.forget_step_memory()
        self.top_react[...] = snap.top_react
        self.cstate[...] = snap.cstate
        self.wstate[...] = snap.wstate
        self.comp[...] = snap.comp
        self.winch[...] = snap.winch
        self.step_count = snap.step
        self.scheme.restore(snap)

    def reset(self) -> None:
        """Back to the settled initial state at t = 0."""
        self.restore(self._initial)
        self.counters[:] = 0
        self.remesh_count = 0
        self.scheme.reset()

    def kernel_data(self) -> KernelData:
        """The arrays the compiled kernel works on and the two hooks of ``advance_steps`` (:class:`KernelData`),
        for callers that run ``kernels.advance`` themselves; they change on a winch remesh and ``set_sea``."""
        return KernelData(self._args, self.settings.array(), self._state, self._ws, self._saved, self.counters,
                          self.comp, self.winch, self.wstate, self._wave_arrays(), self._remesh, self._divergence)

    def _run(self, tops, dt, t_start):
        self.scheme.run(tops, dt, t_start)

    def _divergence(self, st, el, md, t_fail) -> SimulationDivergence:
        """The SimulationDivergence for kernel status ``st`` (element ``el``, last max|δT| ``md``) at ``t_fail``."""
        cause = _CAUSES.get(st, f"status {st}")
        if st == K.FAIL_NEWTON:
            cause = cause.replace("(after step cuts)", f"(after {self.settings.max_step_cuts} step halvings)")
            cause += self._courant_hint(el)
        return SimulationDivergence(t_fail, self._element_name(st, el), cause, int(self.settings.max_iterations),
                                    float(md))

    def _remesh(self):
        """Insert a node near the top of the winch line (payout) or remove one (haul-in), model.md 2.8."""
        from .system import remesh_top
        s = self.system
        seg = int(self.winch[K.W_SEG])
        l_nom = float(self.winch[K.W_LNOM])
        insert = s.l0[seg] > 1.5 * l_nom
        out = remesh_top(s, self.winch_line, insert, l_nom)
        if out is None:          # nothing removable (junction or body right below): keep the short segment
            self.winch[K.W_LNOM] = max(0.5 * float(s.l0[seg]), 1e-6) if not insert else l_nom
            return
        new, node_map, seg_map, info = out
        old_r, old_ang, old_T = self.hist_r.copy(), self.hist_ang.copy(), self.tens_hist.copy()
        old_chart = self.body_chart.copy()
        old_react = self.top_react.copy()
        self.system = new
        self._allocate()
        for i, o in enumerate(node_map):
            if o >= 0:
                self.hist_r[:, i] = old_r[:, o]
        if insert:
            f = info["fraction"]
            lo, up = info["lower"], info["upper"]
            self.hist_r[:, info["inserted"]] = old_r[:, lo] + f * (old_r[:, up] - old_r[:, lo])
        for i, o in enumerate(seg_map):
            if o >= 0:
                self.tens_hist[:, i] = old_T[:, o]
            else:
                self.tens_hist[:, i] = old_T[:, info["split"][0]]
        self.hist_ang[...] = old_ang
        self.body_chart[...] = old_chart
        self.top_react[...] = old_react
        self.winch[K.W_SEG] = new.line(self.winch_line).segments[0]
        self.winch[K.W_LNOM] = l_nom
        if self.comp[K.C_MODE] > 0:
            self.comp[K.C_NODE] = new.comp_node
            self.comp[K.C_SHIP] = new.top_node
        self.remesh_count = getattr(self, "remesh_count", 0) + 1

    # ------------------------------------------------------------------------------------------
    def set_compensator(self, stiffness=None, damping=None, mode=None, command=None):
        """Change the compensator at run time: stiffness/damping within the scene's bounds (semi-active),
        the mode (passive, locked, position, force) and the active command (m or N)."""
        if self.comp[K.C_MODE] == 0:
            raise ValueError("set_compensator: the scene has no [compensator] section")
        (klo, khi), (blo, bhi) = self._comp_bounds
        if stiffness is not None:
            if not (klo <= stiffness <= khi):
                raise ValueError(f"compensator.stiffness: must be within [{klo:g}, {khi:g}] N/m (got {stiffness!r})")
            self.comp[K.C_K] = stiffness
        if damping is not None:
            if not (blo <= damping <= bhi):
                raise ValueError(f"compensator.damping: must be within [{blo:g}, {bhi:g}] N s/m (got {damping!r})")
            self.comp[K.C_B] = damping
        if mode is not None:
            if mode not in self._COMP_MODES:
                raise ValueError(f"compensator.mode: must be one of {sorted(self._COMP_MODES)} (got {mode!r})")
            new = self._COMP_MODES[mode]
            if new in (K.COMP_POSITION,) and self.comp[K.C_MODE] != new:
                self.cstate[K.CS_ACT] = self.compensator_state()["stroke"]
            self.comp[K.C_MODE] = new
        if command is not None:
            if not np.isfinite(command):
                raise ValueError(f"compensator command: must be finite (got {command!r})")
            self.comp[K.C_CMD] = command

    def compensator_state(self):
        """Stroke z (m, + up, 0 = mid-stroke), stroke velocity, end-stop hits, contact flag, deepest penetration."""
        s = self.system
        if s.comp_node < 0:
            raise ValueError("compensator_state: the scene has no [compensator] section")
        z = self.hist_r[:, s.comp_node, 2] - self.hist_r[:, s.top_node, 2]
        return {"stroke": float(z[0]), "stroke_velocity": float((3 * z[0] - 4 * z[1] + z[2]) / (2 * self.dt)),
                "hits": int(self.cstate[K.CS_HITS]), "in_contact": bool(self.cstate[K.CS_CONTACT]),
                "max_penetration": float(self.cstate[K.CS_PEN]), "stiffness": float(self.comp[K.C_K]),
                "damping": float(self.comp[K.C_B])}

    def set_winch(self, speed=None, mode=None, set_tension=None, gain=None, deadband=None):
        """Winch payout speed command (m/s, payout > 0), mode (speed / constant_tension), and the
        constant-tension law's set tension (N), gain ((m/s)/N) and deadband (N)."""
        if self.winch[K.W_MODE] == 0:
            raise ValueError("set_winch: the scene has no [winch] section")
        if speed is not None:
            vmax = self.winch[K.W_VMAX]
            if not (np.isfinite(speed) and abs(speed) <= vmax):
                raise ValueError(f"winch.speed: must be within ±{vmax:g} m/s (got {speed!r})")
            self.winch[K.W_VCMD] = speed
        if mode is not None:
            if mode not in self._WINCH_MODES:
                raise ValueError(f"winch.mode: must be one of {sorted(self._WINCH_MODES)} (got {mode!r})")
            self.winch[K.W_MODE] = self._WINCH_MODES[mode]
        if set_tension is not None:
            if not (np.isfinite(set_tension) and set_tension >= 0):
                raise ValueError(f"winch.set_tension: must be >= 0 N (got {set_tension!r})")
            self.winch[K.W_TSET] = set_tension
        if gain is not None:
            if not (np.isfinite(gain) and gain >= 0):
                raise ValueError(f"winch.gain: must be >= 0 (m/s)/N (got {gain!r})")
            self.winch[K.W_GAIN] = gain
        if deadband is not None:
            if not (np.isfinite(deadband) and deadband >= 0):
                raise ValueError(f"winch.deadband: must be >= 0 N (got {deadband!r})")
            self.winch[K.W_DEADBAND] = deadband

    def winch_state(self):
        """Payout speed (m/s), deployed length of the winch line (m), total paid out (m), segments."""
        if self.winch[K.W_MODE] == 0:
            raise ValueError("winch_state: the scene has no [winch] section")
        lm = self.system.line(self.winch_line)
        return {"speed": float(self.wstate[K.WS_V]), "length": float(self.system.l0[lm.segments].sum()),
                "paid_out": float(self.wstate[K.WS_PAID]), "segments": int(len(lm.segments)),
                "top_segment_length": float(self.system.l0[lm.segments[0]])}

    def advance(self, seconds: float) -> None:
        """Advance by ``seconds`` (rounded to whole steps of ``dt``; 0 does nothing). ``seconds`` must be a
        finite number >= 0 (``ValueError`` otherwise)."""
        ok = isinstance(seconds, (int, float, np.integer, np.floating)) and not isinstance(seconds, (bool, np.bool_))
        sec = float(seconds) if ok else float("nan")
        if not (math.isfinite(sec) and sec >= 0):
            raise ValueError(f"seconds: must be a finite number >= 0 (got {seconds!r})")
        self.advance_steps(int(round(sec / self.settings.dt)))

    #: longest run handed to the kernel in one call (its tow-point positions are an (n, 3) array)
    _MAX_CALL_STEPS = 1 << 20

    def advance_steps(self, n: int) -> None:
        """Advance by ``n`` whole time steps (an integer >= 0; 0 does nothing)."""
        if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 0:
            raise ValueError(f"n: must be an integer number of steps >= 0 (got {n!r})")
        n = int(n)
        while n > self._MAX_CALL_STEPS:
            self._advance_steps(self._MAX_CALL_STEPS)
            n -= self._MAX_CALL_STEPS
        self._advance_steps(n)

    def _advance_steps(self, n: int) -> None:
        if n <= 0:
            return
        dt = self.settings.dt
        tops = self._tow_points(self.step_count + 1, n)
        t0 = self.t
        try:
            self._run(tops, dt, t0)
        except SimulationDivergence as exc:
            # the kernel stopped at the last good step: count the steps that did succeed
            self.step_count += int(round((exc.time - t0) / dt)) - 1
            raise
        self.step_count += n

    _BLOCK = 2048
    #: block length (steps) for Δt ≥ 0.05 s: a 2048-step block spans 100–600 s there, and a short run would
    #: pay for evaluating the vessel motion over the whole block (~10 µs per step in an irregular sea)
    _BLOCK_COARSE = 256
    #: ... but only where the path may use the wave phase recurrence: an exact path (no sea-state vessel motion) costs
    #: ~0.1 µs per step evaluated in one call (``TowPointBuffer.block``), so it keeps the long block at every Δt

    def _tow_point_buffer(self):
        buf = self.__dict__.get("_tp_buffer")
        if buf is None:
            from .tow_point import TowPointBuffer
            buf = self._tp_buffer = TowPointBuffer(self)
        return buf

    def _tow_points(self, first, n):
        """Tow-point positions at steps first … first+n−1, evaluated in fixed, aligned blocks of steps (fixed
        blocks keep every step computed the same way whatever the caller's chunking, so runs stay bit-for-bit
        reproducible, and amortise vessel-motion evaluation). In a sea on a straight leg the wave part comes
        from the phase recurrence the environments use (:mod:`towenv.core.tow_point`: ≤ 1e-9 m from the
        exact sum, ~10× cheaper)."""
        B = self._BLOCK if (self.settings.dt < 0.05 or not self._tow_point_buffer().recurrence_possible()) \
            else self._BLOCK_COARSE
        cache = self.__dict__.setdefault("_top_blocks", {})
        out = np.empty((n, 3))
        i = 0
        while i < n:
            step = first + i
            b = step // B
            if b not in cache:
                if len(cache) > 4:
                    cache.clear()
                cache[b] = self._tow_point_buffer().block(b * B, B)
                if self.settings.planar and np.ptp(cache[b][:, 1]) > 1e-9:
                    cache.pop(b)
                    raise ValueError("solver.planar: the tow-point path moves laterally (vessel motion from the "
                                     "sea/RAOs or the motion record has sway, roll or yaw); use the 3-D model")
            j = step - b * B
            m = min(B - j, n - i)
            out[i:i + m] = cache[b][j:j + m]
            i += m
        return out

    # ------------------------------------------------------------------------------------------
    def transverse_courant(self) -> np.ndarray:
        """Per segment, the transverse Courant number c_T·Δt/l of the initial (static) state, with
        c_T = √(T / (μ + μ_added)): short, taut segments at a long Δt make it large, and the tension
        iteration's convergence degrades above ~2 (model.md 5.9)."""
        s = self.system
        n = min(len(self.static_tensions), len(s.l0))
        T = np.maximum(self.static_tensions[:n], 0.0)
        m_add = 0.25 * np.pi * s.diam[:n] ** 2 * s.can[:n] * s.rho
        return self.settings.dt * np.sqrt(T / (s.mu[:n] + m_add)) / s.l0[:n]

    def _courant_hint(self, seg: int) -> str:
        """For a Newton failure in segment ``seg``: why, when its Courant number is the likely reason."""
        try:
            c = float(self.transverse_courant()[seg])
        except (IndexError, ValueError, AttributeError):
            return ""
        if not c > 1.5:
            return ""
        dt = self.settings.dt
        return (f"; its transverse Courant number c_T·Δt/l is {c:.2g}: the segment is short for Δt = {dt:g} s "
                f"(the tension iteration needs it below ~1.5-2, model.md 5.9) — use fewer segments on this "
                f"line or Δt <= {dt * 1.5 / c:.2g} s")

    def _node_name(self, j: int) -> str:
        """``"node 3 of line 'primary' (global 3)"`` (a body's node: ``"node 9 (body 'fish')"``)."""
        for b in self.system.bodies:
            if b.node == j:
                return f"node {j} (body {b.name!r})"
        for lm in self.system.lines:
            if j in lm.nodes:
                return f"node {int(np.where(lm.nodes == j)[0][0])} of line {lm.name!r} (global {j})"
        return f"node {j}"

    def _element_name(self, status, el):
        s = self.system
        if el < 0:
            return "the system"
        if status == K.FAIL_ANGLE:
            names = [b.name for b in s.bodies if b.rigid_index == el]
            return f"body {names[0]!r}" if names else f"body {el}"
        if status in (K.FAIL_NEWTON, K.FAIL_STRETCH):
            for lm in s.lines:
                if el in lm.segments:
                    return f"segment {int(np.where(lm.segments == el)[0][0])} of line {lm.name!r} (global {el})"
            return f"segment {el}"
        return f"element {el}"

    @property
    def positions(self) -> np.ndarray:
        return self.hist_r[0]

    @property
    def velocities(self) -> np.ndarray:
        return (3 * self.hist_r[0] - 4 * self.hist_r[1] + self.hist_r[2]) / (2 * self.settings.dt)

    @property
    def tensions(self) -> np.ndarray:
        return self.tens_hist[0]

    @property
    def top_force(self) -> np.ndarray:
        """Force of the cable on the vessel at the tow point (N, global axes)."""
        return self.top_react.copy()

    @property
    def top_tension(self) -> float:
        """Magnitude of the tow-point reaction (N)."""
        return float(np.linalg.norm(self.top_react))

    def line_state(self, name):
        lm = self.system.line(name)
        return {"positions": self.positions[lm.nodes].copy(), "tensions": self.tensions[lm.segments].copy()}

    def anchor_force(self, name) -> np.ndarray:
        """Force of line ``name`` on its anchor (N, global axes), from the last step's loads."""
        s = self.system
        node = int(s.line(name).nodes[-1])
        if node not in s.anchors:
            raise ValueError(f"line {name!r} does not end at an anchor")
        r = self.positions
        v = self.velocities
        ws = self._ws
        tang, stretched, drag, bmat, madd, mnode, bnode, fnode = (ws.tang, ws.stretched, ws.drag, ws.bmat, ws.madd,
                                                                  ws.mnode, ws.bnode, ws.fnode)
        K.segment_loads(r, v, s.seg_lo, s.seg_up, s.l0, s.diam, s.mu, s.cn, s.ct, s.can, s.cat, s.rho, s.g,
                        s.cur_z, s.cur_v, tang, stretched, drag, bmat, madd)
        K.node_assembly(r, v, s.node_kind, s.node_nseg, s.node_segs, s.node_sgn, s.l0, s.diam, s.mu, s.rho, s.g,
                        drag, bmat, madd, s.pb_mass, s.pb_vol, s.pb_cda, s.pb_ca, s.cur_z, s.cur_v, mnode, bnode,
                        fnode)
        out = np.zeros(3)
        K.node_reaction(node, r, r, r, r, self.settings.dt, s.node_nseg, s.node_segs, s.node_sgn, tang,
                        self.tensions, mnode, fnode, out)
        return out

    def tow_point_state(self):
        """Vessel tow point (ship side of any compensator): position, velocity and acceleration from the
        stored history (what a tow-point IMU measures), global axes."""
        h = self.hist_r[:, self.system.top_node]
        dt = self.settings.dt
        return {"position": h[0].copy(), "velocity": (3 * h[0] - 4 * h[1] + h[2]) / (2 * dt),
                "acceleration": (h[0] - 2 * h[1] + h[2]) / (dt * dt)}

    def node_tensions(self, name) -> np.ndarray:
        """Cable tension at each node of a line (top first), free of the half-segment bias of segment
        tensions (verification.md V1/V2): at a node, the force carried by the cable there is the
        adjacent segment's tension vector corrected by the external load (wet weight + drag) of the half
        segment in between; interior nodes average the estimates from both sides. The vessel end uses
        the tow-point reaction."""
        s = self.system
        lm = s.line(name)
        r = self.positions
        v = self.velocities
        tang, stretched, drag, bmat, madd = (np.empty((s.n_segments, 3)), np.empty(s.n_segments),
                                              np.empty((s.n_segments, 2, 3)), np.empty((s.n_segments, 2, 3, 3)),
                                              np.empty((s.n_segments, 3, 3)))
        K.segment_loads(r, v, s.seg_lo, s.seg_up, s.l0, s.diam, s.mu, s.cn, s.ct, s.can, s.cat, s.rho, s.g,
                        s.cur_z, s.cur_v, tang, stretched, drag, bmat, madd)
        T = self.tensions
        est = [[] for _ in range(len(lm.nodes))]
        for k, seg in enumerate(lm.segments):
            wet = (s.mu[seg] - s.rho * 0.25 * np.pi * s.diam[seg] ** 2) * s.g * s.l0[seg]
            f = T[seg] * tang[seg]
            half_up = 0.5 * drag[seg, 1] - np.array([0.0, 0.0, 0.5 * wet])
            half_lo = 0.5 * drag[seg, 0] - np.array([0.0, 0.0, 0.5 * wet])
            est[k].append(np.linalg.norm(f - half_up))       # upper node of the segment
            est[k + 1].append(np.linalg.norm(f + half_lo))   # lower node
        out = np.array([np.mean(e) for e in est])
        if lm.nodes[0] == s.top_node:
            out[0] = self.top_tension
        return out

    def body_state(self, name):
        """Position and velocity of the body's tow point (global), its attitude and body rates.

        ``euler``: (roll, pitch, yaw) of the body's attitude (docs/scene-format.md convention). While the
        body has never been re-charted (pitch never beyond ±60°) these are the integrated angles (yaw
        continuous, it may exceed ±180° in turns); afterwards they are extracted from the attitude with
        pitch in [−90°, 90°] and roll, yaw in (−180°, 180°]: a body pitched past the vertical shows pitch
        folding back with roll and yaw jumping by 180° (the same attitude) — use ``rotation`` or
        ``quaternion`` for a continuous attitude.
        ``rotation``: R (body -> global: columns are the body axes x′, y′, z′ in global components);
        ``quaternion``: (w, x, y, z) of R, w ≥ 0. ``omega``: body rates (p, q, r), body axes.
        Point bodies: zero angles and rates, identity rotation."""
        bm = self.system.body(name)
        pos = self.positions[bm.node].copy()
        vel = self.velocities[bm.node].copy()
        if bm.rigid_index >= 0:
            b = bm.rigid_index
            lam = np.empty((3, 3))
            K.body_rotation(self.hist_ang[0, b], self.body_chart[b], lam)
            if _is_identity(self.body_chart[b]):
                ang = self.hist_ang[0, b].copy()      # never re-charted: the stored angles are the attitude
            else:
                ang = np.empty(3)
                K.euler_from_rotation(lam, ang)
            # body rates from the local (chart) angles: the chart is constant, so they are the true rates
            dang = (3 * self.hist_ang[0, b] - 4 * self.hist_ang[1, b] + self.hist_ang[2, b]) / (2 * self.settings.dt)
            w = np.empty(3)
            K.euler_rates_to_omega(self.hist_ang[0, b], dang, w)
            rot = lam.T.copy()
        else:
            ang = np.zeros(3)
            w = np.zeros(3)
            rot = np.eye(3)
        return {"position": pos, "velocity": vel, "euler": ang, "omega": w, "rotation": rot,
                "quaternion": quaternion_from_rotation(rot)}

    @property
    def stats(self):
        c = self.counters
        return self.scheme.stats({
            "steps": int(c[L.N_STEPS]), "iterations": int(c[L.N_ITERATIONS]),
            "max_iterations": int(c[L.N_MAX_ITERATIONS]), "step_cuts": int(c[L.N_STEP_CUTS]),
            "recharts": int(c[L.N_RECHARTS]), "mean_iterations": float(c[L.N_ITERATIONS] / max(c[L.N_STEPS], 1))})


def quaternion_from_rotation(R) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w ≥ 0, of a rotation matrix R (Shepperd's method: no loss of
    accuracy near 180°)."""
    R = np.asarray(R, float)
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    k = int(np.argmax([tr, R[0, 0], R[1, 1], R[2, 2]]))
    if k == 0:
        w = 0.5 * math.sqrt(max(1.0 + tr, 0.0))
        q = np.array([w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w)])
    else:
        i = k - 1
        j, m = (i + 1) % 3, (i + 2) % 3
        x = 0.5 * math.sqrt(max(1.0 + R[i, i] - R[j, j] - R[m, m], 0.0))
        q = np.empty(4)
        q[1 + i] = x
        q[0] = (R[m, j] - R[j, m]) / (4 * x)
        q[1 + j] = (R[j, i] + R[i, j]) / (4 * x)
        q[1 + m] = (R[m, i] + R[i, m]) / (4 * x)
    if q[0] < 0:
        q = -q
    return q / np.linalg.norm(q)


def _is_identity(c) -> bool:
    return c[0, 0] == 1.0 and c[1, 1] == 1.0 and c[2, 2] == 1.0


def physical_attitude(chart, ang):
    """Physical attitude from recorded chart-local angles (vectorised over leading axes): ``chart`` (..., 3, 3)
    the body charts (``Simulator.body_chart``), ``ang`` (..., 3) the local Euler angles (``hist_ang[0]``).
    Returns (euler (..., 3), R (..., 3, 3) body -> global), with the same rule as ``Simulator.body_state``:
    where the chart is the identity the angles are passed through unchanged, elsewhere they are extracted
    from R with pitch in [−90°, 90°]."""
    chart = np.asarray(chart, float)
    ang = np.asarray(ang, float)
    b, a, g = ang[..., 0], ang[..., 1], ang[..., 2]
    cb, sb, ca, sa, cg, sg = np.cos(b), np.sin(b), np.cos(a), np.sin(a), np.cos(g), np.sin(g)
    loc = np.stack([np.stack([cg * ca, sg * ca, -sa], -1),
                    np.stack([-sg * cb + cg * sa * sb, cg * cb + sg * sa * sb, ca * sb], -1),
                    np.stack([cg * sa * cb + sg * sb, sg * sa * cb - cg * sb, ca * cb], -1)], -2)
    lam = loc @ chart
    c = np.hypot(lam[..., 0, 0], lam[..., 0, 1])
    pitch = np.arctan2(-lam[..., 0, 2], c)
    ok = c > 1e-12
    roll = np.where(ok, np.arctan2(lam[..., 1, 2], lam[..., 2, 2]), 0.0)
    yaw = np.where(ok, np.arctan2(lam[..., 0, 1], lam[..., 0, 0]), np.arctan2(-lam[..., 1, 0], lam[..., 1, 1]))
    ident = (chart[..., 0, 0] == 1.0) & (chart[..., 1, 1] == 1.0) & (chart[..., 2, 2] == 1.0)
    euler = np.where(ident[..., None], ang, np.stack([roll, pitch, yaw], -1))
    return euler, np.swapaxes(lam, -1, -2)


def time_step_guide(T_keep: float, scheme: str = "houbolt", tolerance: str = "1%") -> float:
    """Largest Δt keeping amplitude decay and period elongation per period within 1 % (or 5 %) for
    the shortest period ``T_keep`` you need resolved (model.md 8.1/8.3: Houbolt T/42 and T/23)."""
    table = {("houbolt", "1%"): 0.024, ("houbolt", "5%"): 0.044}
    try:
        return T_keep * table[(scheme, tolerance)]
    except KeyError:
        raise ValueError(f"time_step_guide: scheme must be 'houbolt' and tolerance '1%' or '5%' "
                         f"(got {scheme!r}, {tolerance!r})") from None


def thesis_time_step(l_min: float, EA: float, mu: float) -> float:
    """The thesis's guide (5.188): Δt ≤ l_min/(10 c_L), c_L = √(EA/μ). One tenth of the explicit CFL
    limit: very conservative for this implicit solver (model.md 8.2)."""
    return l_min / (10.0 * math.sqrt(EA / mu))


def transverse_courant_time_step(l_min: float, T_max: float, mu: float, mu_added: float, courant: float = 0.5):
    """Δt keeping the transverse Courant number c_T Δt / l ≤ ``courant`` — the practical convergence limit
    of the quasi-Newton tension iteration (model.md 5.9)."""
    return courant * l_min / math.sqrt(T_max / (mu + mu_added))
