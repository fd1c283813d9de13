"""Run a single-line + point-body towenv scene in MoorDyn v2 (the ``peer`` extra) for cross-checks.

The scene (a dict, path, embedded name or :class:`towenv.Scene`) must have exactly one cable from the
vessel tow point to a point body (``kind = "ball"`` or ``"clump"``) or to a free end, no current, no sea,
no compensator and no winch — the shape of the verification "peer deck" (``verification.md``) and of
``ablow_turn_1km``. The MoorDyn v2 input file is built with:

* ``LINE TYPES``: Diam = D, Mass/m = μ, EA, BA = −ζ (MoorDyn's damping-ratio convention), EI = 0,
  Cd = C_n, Ca = C_an, **CdAx = C_t/π** (towenv's tangential coefficient is on D·l, MoorDyn's on π·D·l),
  CaAx = C_at;
* ``POINTS``: a ``Coupled`` tow point and a ``Free`` body point (mass, volume, isotropic CdA, C_a);
* ``OPTIONS``: dtM, tScheme, water density, g, a water depth far below the system (no seabed contact).

The tow point follows the *same* path as towenv (``towenv.Simulator(scene).path.position(t)``), fed
the MoorDyn way (verification.md, gotcha 1): each coupling step k passes the position at the **start** of
the step, x(t_k), and the constant velocity (x(t_{k+1}) − x(t_k))/Δt over it. MoorDyn's console output
is suppressed by redirecting file descriptor 1 (gotcha 5) and kept in ``MoorDynResult.log``.

towenv starts a towed scene from the steady tow at the path's initial velocity. MoorDyn's initial
condition solver only finds a *static* hang, so ``settle_time`` seconds of steady towing at that velocity
are run before t = 0 (not timed, not recorded). Only the ``Step`` calls of the recorded phase are timed
(not ``Create``/``Init`` nor the settling).

Damping conventions: MoorDyn's ``BA = −ζ`` gives a segment damping coefficient ζ·l·√(EA·μ) (N·s); towenv's
explicit ``axial_damping_ratio`` ζ' gives 2ζ'·l·√(EA·μ). So MoorDyn ``BA = −ζ`` equals towenv
``axial_damping_ratio = ζ/2`` (:func:`towenv_axial_damping_ratio`).
"""
from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

INSTALL_HINT = ("MoorDyn is not installed: the MoorDyn cross-checks need the optional 'peer' extra "
                "(pip install 'towenv[peer]' or pip install moordyn)")


class MoorDynUnsupported(ValueError):
    """The scene cannot be expressed as a single MoorDyn line + point body."""


def moordyn_available() -> bool:
    try:
        import moordyn  # noqa: F401
    except ImportError:
        return False
    return True


def require_moordyn():
    """Import and return the ``moordyn`` module, or raise ``ImportError`` with an install hint."""
    try:
        import moordyn
    except ImportError as exc:
        raise ImportError(INSTALL_HINT) from exc
    return moordyn


def towenv_axial_damping_ratio(moordyn_zeta: float) -> float:
    """towenv ``solver.axial_damping_ratio`` giving the same segment damping as MoorDyn ``BA = −zeta``."""
    return 0.5 * float(moordyn_zeta)


# ---------------------------------------------------------------------------------------------------
# Input file
# ---------------------------------------------------------------------------------------------------
@dataclass
class _Deck:
    length: float
    segments: int
    diameter: float
    mu: float
    EA: float
    cn: float
    ct: float
    can: float
    cat: float
    rho: float
    g: float
    body: dict | None          # mass, volume, cda, ca (None: free end)
    body_name: str | None
    line_name: str


def deck_parameters(scene) -> _Deck:
    from ..scene import load_scene
    sc = load_scene(scene)
    probs = []
    if len(sc.lines) != 1:
        probs.append(f"{len(sc.lines)} lines (exactly one cable is supported)")
    ln = sc.lines[0]
    if ln.top_kind != "vessel":
        probs.append("the cable's top is not the vessel tow point")
    cur = sc.current
    if cur.velocity is not None and any(abs(c) > 0 for c in cur.velocity) or cur.depths is not None:
        probs.append("a current (not translated)")
    if sc.sea is not None or sc.vessel.model is not None or sc.vessel.rao_file is not None \
            or sc.vessel.motion_file is not None:
        probs.append("sea-state vessel motion (use excitation/manoeuvres instead)")
    if sc.compensator is not None or sc.winch is not None:
        probs.append("a compensator or winch")
    juncs = [x.top.distance for x in sc.lines if x.top_kind == "line" and x.top.line == ln.name]
    segs = ln.span_segments(juncs)
    if len(segs) != 1:
        probs.append("junctions on the cable")
    body = None
    bname = ln.bottom_body
    if bname is not None:
        b = next(bb for bb in sc.bodies if bb.name == bname)
        if b.is_rigid:
            probs.append(f"body {bname!r} is a {b.kind} (6-DOF lifting body); only point bodies (ball, clump)")
        else:
            body = dict(mass=b.mass, volume=b.volume, cda=b.drag_area, ca=b.added_mass_coefficient)
    elif ln.bottom != "free":
        probs.append("the cable's bottom is an anchor")
    if len(sc.bodies) > (1 if bname else 0):
        probs.append("bodies not at the cable's end")
    if probs:
        raise MoorDynUnsupported(f"scene {sc.name!r} cannot be run in MoorDyn: " + "; ".join(probs))
    return _Deck(ln.length, int(segs[0]), ln.diameter, ln.mass_per_length, ln.EA, ln.cn, ln.ct, ln.can, ln.cat,
                 sc.water.density, sc.water.gravity, body, bname, ln.name)


def moordyn_input(scene, dtM: float = 2e-4, scheme: str = "RK2", zeta: float = 1.0, start=(0.0, 0.0, 0.0),
                  segments: int | None = None, water_depth: float | None = None) -> str:
    """MoorDyn v2 input file text for a single-line + point-body scene.

    ``zeta``: segment damping ratio in MoorDyn's convention (written as ``BA = −zeta``; 0 = undamped).
    ``start``: the coupled tow point's position (the free point is placed one cable length below it;
    MoorDyn's initial-condition solver then finds the static hang). ``segments`` overrides the scene's.
    """
    d = deck_parameters(scene)
    n = int(segments or d.segments)
    x, y, z = (float(v) for v in start)
    depth = water_depth if water_depth is not None else max(1000.0, 10.0 * d.length) - z
    r = repr
    if d.body is not None:
        b = d.body
        body_row = f"2      Free      {r(x)}  {r(y)}  {r(z - d.length)}  {r(b['mass'])}  {r(b['volume'])}  " \
                   f"{r(b['cda'])}  {r(b['ca'])}"
    else:
        body_row = f"2      Free      {r(x)}  {r(y)}  {r(z - d.length)}  0.0  0.0  0.0  0.0"
    lines = [
        "--------------------- MoorDyn Input File ------------------------------------",
        "towenv peer deck (generated by towenv.peer.moordyn_runner)",
        "----------------------- LINE TYPES ------------------------------------------",
        "TypeName   Diam    Mass/m     EA         BA/-zeta    EI         Cd     Ca     CdAx    CaAx",
        "(name)     (m)     (kg/m)     (N)        (N-s/-)     (N-m^2)    (-)    (-)    (-)     (-)",
        f"cable  {r(d.diameter)}  {r(d.mu)}  {r(d.EA)}  {r(-abs(float(zeta)))}  0.0  {r(d.cn)}  {r(d.can)}  "
        f"{r(d.ct / math.pi)}  {r(d.cat)}",
        "---------------------- POINTS --------------------------------",
        "ID     Type      X        Y         Z         Mass   Volume   CdA    Ca",
        "(#)    (-)       (m)      (m)       (m)       (kg)   (m^3)    (m^2)  (-)",
        f"1      Coupled   {r(x)}  {r(y)}  {r(z)}  0.0  0.0  0.0  0.0",
        body_row,
        "---------------------- LINES --------------------------------------",
        "ID    LineType   AttachA  AttachB  UnstrLen  NumSegs   Outputs",
        "(#)   (name)     (#)      (#)      (m)       (-)       (-)",
        f"1     cable      2        1        {r(d.length)}  {n}  -",
        "---------------------- OPTIONS -----------------------------------------",
        f"{r(float(dtM))}   dtM       - mooring time step (s)",
        f"{scheme}   tScheme   - time integration scheme",
        f"{r(d.rho)}   WtrDnsty  - water density (kg/m^3)",
        f"{r(d.g)}   g         - gravity (m/s^2)",
        f"{r(float(depth))}   WtrDpth   - water depth (m): far below the system, no seabed contact",
        "1.0      dtIC      - IC convergence analysis interval (s)",
        "200.0    TmaxIC    - max time for IC generation (s)",
        "1e-7     threshIC  - IC convergence threshold",
        "0        writeLog",
        "1        disableOutput",
        "------------------------- need this line --------------------------------------",
    ]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------------
# Running
# ---------------------------------------------------------------------------------------------------
@dataclass
class MoorDynResult:
    """MoorDyn time series at the coupling steps: t[0] = 0 is the state after Init/settling, or t[0] = the
    first coupling step when the run started from a serialized ``initial_state``."""
    t: np.ndarray
    top_force: np.ndarray          # (n, 3) force of the cable on the coupled tow point (from Step), N
    body_position: np.ndarray      # (n, 3) free point, m
    dtM: float
    scheme: str
    zeta: float
    segments: int
    dt_coupling: float
    wall_step: float = float("nan")     # s spent in Step calls of the recorded phase
    wall_init: float = float("nan")     # s in Create + Init
    wall_settle: float = float("nan")   # s of settling steps (not part of wall_step)
    failed: str | None = None           # why MoorDyn stopped (error code/exception/non-finite force)
    log: str = ""
    input_text: str = ""
    meta: dict = field(default_factory=dict)

    @property
    def top_tension(self) -> np.ndarray:
        return np.linalg.norm(self.top_force, axis=1)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0]) if len(self.t) > 1 else 0.0

    @property
    def wall_per_sim_second(self) -> float:
        return self.wall_step / self.duration if self.duration > 0 else float("nan")

    @property
    def real_time_factor(self) -> float:
        return self.duration / self.wall_step if self.wall_step > 0 else float("nan")


@contextlib.contextmanager
def _quiet(capture_path):
    """Redirect the process's file descriptors 1 and 2 (C++ iostreams included) to a file."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    fd = os.open(capture_path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    try:
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        yield
    finally:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        except Exception:  # pragma: no cover
            pass
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])
        os.close(fd)


def _setup(sc, d, dtM, scheme, zeta, dt_coupling, settle_time, segments):
    path = _path_of(sc)
    U = np.asarray(path.initial_velocity(), float)
    speed = float(np.linalg.norm(U))
    if settle_time is None:
        settle_time = 0.0 if speed == 0 else max(300.0, 10.0 * d.length / speed)
    n_settle = int(round(settle_time / dt_coupling))
    x0 = path.position(np.array([0.0]))[0]
    start = x0 - n_settle * dt_coupling * U
    text = moordyn_input(sc, dtM=dtM, scheme=scheme, zeta=zeta, start=start, segments=segments)
    return path, U, speed, n_settle, x0, start, text


def settled_state(scene, settle_time: float | None = None, dtM: float | None = None, scheme: str = "RK4",
                  zeta: float = 0.5, dt_coupling: float = 0.05, segments: int | None = None,
                  quiet: bool = True) -> tuple[bytes, dict]:
    """MoorDyn state (``moordyn.Serialize`` bytes) after ``settle_time`` s of steady towing at the path's
    initial velocity, ending with the tow point at x(0): pass it as ``run_moordyn(initial_state=...)`` to
    start several runs (other dtM) from the same steady tow. ``dtM`` defaults to 0.7 l/c_L with RK4
    (stable with ζ ≤ 0.5). Returns (state, info) with info = settle time, wall time, final tension.

    A state serialized with RK4 loads into RK2 and RK4 instances (moordyn 2.7.2); one serialized with RK2
    does **not** load into RK4 ("A state variable with … instances cannot be deserialized"), and loading
    into an Euler instance aborts the process — so settle with RK4 and run RK2/RK4 only."""
    md = require_moordyn()
    from ..scene import load_scene
    sc = load_scene(scene)
    d = deck_parameters(sc)
    n = int(segments or d.segments)
    if dtM is None:
        dtM = 0.7 * (d.length / n) / math.sqrt(d.EA / d.mu)
    path, U, speed, n_settle, x0, start, text = _setup(sc, d, dtM, scheme, zeta, dt_coupling, settle_time, n)
    with tempfile.TemporaryDirectory(prefix="towenv_moordyn_") as tmp:
        inp = Path(tmp) / "towenv_peer.txt"
        inp.write_text(text)
        logp = Path(tmp) / "console.txt"
        with (_quiet(str(logp)) if quiet else contextlib.nullcontext()):
            s = md.Create(str(inp))
            try:
                md.Init(s, list(start), list(U))
                w0 = time.perf_counter()
                f = [float("nan")] * 3
                ul = list(U)
                for k in range(n_settle):
                    f = md.Step(s, list(start + k * dt_coupling * U), ul, k * dt_coupling, dt_coupling)
                wall = time.perf_counter() - w0
                state = md.Serialize(s)
            finally:
                md.Close(s)
    return state, dict(settle_time=n_settle * dt_coupling, wall=wall, top_tension=float(np.linalg.norm(f)),
                       dtM=dtM, scheme=scheme, zeta=zeta, segments=n)


def run_moordyn(scene, duration: float, dtM: float = 2e-4, scheme: str = "RK2", zeta: float = 1.0,
                dt_coupling: float = 0.01, settle_time: float | None = None, segments: int | None = None,
                initial_state: bytes | None = None, quiet: bool = True) -> MoorDynResult:
    """Run ``scene`` in MoorDyn for ``duration`` s with the towenv tow-point path.

    ``dtM``/``scheme``: MoorDyn's internal step and scheme (RK2, RK4, Euler, ...); ``zeta``: segment
    damping ratio (MoorDyn convention, BA = −zeta); ``dt_coupling``: the Step interval; ``segments``
    overrides the scene's count. The start at t = 0 is either ``initial_state`` (from
    :func:`settled_state`, same segment count) or MoorDyn's static initial condition followed by
    ``settle_time`` s of steady towing at the path's initial velocity (default: 0 for a scene at rest,
    else max(300 s, 10 L/U); the slow drift of a towed body from the hang decays over minutes).

    Returns a :class:`MoorDynResult`. If MoorDyn fails (error code, exception or non-finite force) the
    series end at the last good step and ``failed`` says why — nothing is silently dropped.
    """
    md = require_moordyn()
    import cmoordyn

    from ..scene import load_scene
    sc = load_scene(scene)
    d = deck_parameters(sc)
    if initial_state is not None:
        if scheme not in ("RK2", "RK4"):
            # moordyn 2.7.2 aborts the whole process when a serialized RK state is loaded into e.g. Euler
            raise ValueError(f"initial_state: only RK2/RK4 runs can start from a serialized state (got {scheme!r})")
        settle_time = 0.0
    path, U, speed, n_settle, x0, start, text = _setup(sc, d, dtM, scheme, zeta, dt_coupling, settle_time,
                                                       segments)
    n_steps = int(round(duration / dt_coupling))
    tk = np.arange(n_steps + 1) * dt_coupling
    xs = path.position(tk)
    vs = np.diff(xs, axis=0) / dt_coupling
    t_rec = np.full(n_steps + 1, np.nan)
    f_rec = np.full((n_steps + 1, 3), np.nan)
    b_rec = np.full((n_steps + 1, 3), np.nan)
    res = MoorDynResult(t=t_rec, top_force=f_rec, body_position=b_rec, dtM=float(dtM), scheme=scheme,
                        zeta=float(zeta), segments=int(segments or d.segments), dt_coupling=float(dt_coupling),
                        input_text=text)
    with tempfile.TemporaryDirectory(prefix="towenv_moordyn_") as tmp:
        inp = Path(tmp) / "towenv_peer.txt"
        inp.write_text(text)
        logp = Path(tmp) / "console.txt"
        sys_ = None
        n_done = -1
        phase = "in Create/Init"
        try:
            with (_quiet(str(logp)) if quiet else contextlib.nullcontext()):
                w0 = time.perf_counter()
                sys_ = md.Create(str(inp))
                if sys_ is None:
                    raise RuntimeError("moordyn.Create returned None")
                if initial_state is not None:
                    md.Init_NoIC(sys_, list(start), list(U))
                    phase = "loading the initial state"
                    md.Deserialize(sys_, initial_state)
                else:
                    rc = md.Init(sys_, list(start), list(U))
                    if rc not in (0, None):
                        raise RuntimeError(f"moordyn.Init returned error code {rc}")
                res.wall_init = time.perf_counter() - w0
                res.meta["dtM_effective"] = float(cmoordyn.get_dt(sys_))
                point = md.GetPoint(sys_, 2)
                # settling: steady towing at the initial velocity up to t = 0 (position x(t_k) at step start)
                phase = "while settling"
                w0 = time.perf_counter()
                t_md = 0.0
                f = None
                ulist = list(U)
                for k in range(n_settle):
                    f = md.Step(sys_, list(start + k * dt_coupling * U), ulist, t_md, dt_coupling)
                    t_md += dt_coupling
                res.wall_settle = time.perf_counter() - w0
                if initial_state is None:
                    # (after Deserialize the point getters are stale until the first Step: no t = 0 sample then)
                    t_rec[0] = 0.0
                    if f is not None:
                        f_rec[0] = f
                    b_rec[0] = md.GetPointPos(point)
                n_done = 0
                wall = 0.0
                pc = time.perf_counter
                xl = xs.tolist()
                vl = vs.tolist()
                for k in range(n_steps):
                    a = pc()
                    f = md.Step(sys_, xl[k], vl[k], t_md, dt_coupling)
                    wall += pc() - a
                    t_md += dt_coupling
                    if f is None or not (math.isfinite(f[0]) and math.isfinite(f[1]) and math.isfinite(f[2])):
                        res.failed = (f"MoorDyn {scheme} at dtM = {dtM:g} s: non-finite force at "
                                      f"t = {tk[k + 1]:.3f} s")
                        break
                    t_rec[k + 1] = tk[k + 1]
                    f_rec[k + 1] = f
                    b_rec[k + 1] = md.GetPointPos(point)
                    n_done = k + 1
                res.wall_step = wall
        except Exception as exc:  # MoorDyn raises RuntimeError("... error integrating") on a blow-up
            where = f"at t = {tk[n_done + 1]:.3f} s" if 0 <= n_done < n_steps else phase
            res.failed = f"MoorDyn {scheme} at dtM = {dtM:g} s failed {where}: {exc}"
        finally:
            if sys_ is not None:
                with (_quiet(str(logp)) if quiet else contextlib.nullcontext()):
                    try:
                        md.Close(sys_)
                    except Exception:  # pragma: no cover
                        pass
            if logp.exists():
                res.log = logp.read_text(errors="replace")
    if res.failed:
        errs = [ln.strip() for ln in res.log.splitlines() if ln.startswith("ERR")]
        if errs:
            res.failed += f" [{errs[-1][-120:]}]"
    m = ~np.isnan(t_rec)
    res.t, res.top_force, res.body_position = t_rec[m], f_rec[m], b_rec[m]
    if len(res.t) > 1 and np.isnan(res.top_force[0]).any():
        res.top_force[0] = res.top_force[1]     # no settling step taken (static start): first step's force
    res.meta.update(settle_time=n_settle * dt_coupling, input_speed=speed)
    return res


def _path_of(scene):
    """The towenv tow-point path of a scene (``towenv.Simulator(scene).path``) without building the
    initial state twice: a Simulator is cheap for these scenes, so simply build one."""
    from ..core.simulator import Simulator
    return Simulator(scene).path
