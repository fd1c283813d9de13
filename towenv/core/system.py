"""Flat-array description of a towed system (nodes, segments, bodies), built from a validated scene.

Numbering: every line is discretised from its top end (toward the ship) to its bottom end. A segment's
``upper`` node is the one toward the ship. Node kinds: ``FREE`` (dynamic), ``PRESCRIBED_TOP`` (the
vessel tow point, or the compensator/winch top) and ``PRESCRIBED_AFT`` (an aft tow point carried by a
body, top of a series-tow tail cable).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from .layout import (BODY_PARAM, BP_ADDED_CORIOLIS, BP_ADDED_COUPLED, BP_ADDED_COUPLING, BP_ADDED_INERTIA,  # noqa: F401
                     BP_EXTERNAL_FORCE, BP_HAS_EXTERNAL,
                     BP_ADDED_MASS, BP_AFT_TOW_POINT, BP_AREA, BP_CB, BP_CG,
                     BP_INERTIA, BP_LENGTH, BP_LIFT_SLOPE, BP_MASS, BP_QUAD_ROT_DAMPING, BP_REDUCED_DOF,
                     BP_ROT_DAMPING, BP_TAIL_MASS, BP_VOLUME)

from .kernels import COMPENSATOR, FREE, PRESCRIBED_AFT, PRESCRIBED_FIXED, PRESCRIBED_TOP

from .model import MAX_SEGS_PER_NODE, Bodies, Segments, Topology, Water
MAX_TABLE = 64


@dataclass
class LineMap:
    """Where a scene line lives in the flat arrays (nodes listed top → bottom)."""
    name: str
    nodes: np.ndarray          # node indices, top first
    segments: np.ndarray       # segment indices, top first
    length: float


@dataclass
class BodyMap:
    name: str
    kind: str                  # fish | depressor | ball | clump
    node: int                  # tow-point node
    rigid_index: int           # index in the rigid-body arrays, -1 for point bodies
    aft_node: int = -1


@dataclass
class System:
    # topology
    seg_lo: np.ndarray
    seg_up: np.ndarray
    seg_uplocal: np.ndarray
    node_kind: np.ndarray
    node_nseg: np.ndarray
    node_segs: np.ndarray
    node_sgn: np.ndarray
    order: np.ndarray
    pos: np.ndarray
    node_parent: np.ndarray     # parent in the static/elimination tree (-1 at the top)
    node_up_seg: np.ndarray     # segment toward the ship (-1 for prescribed nodes)
    post_order: np.ndarray      # nodes, leaves first
    top_node: int
    # segment properties
    l0: np.ndarray
    diam: np.ndarray
    mu: np.ndarray
    cn: np.ndarray
    ct: np.ndarray
    can: np.ndarray
    cat: np.ndarray
    ea: np.ndarray
    # bodies
    body_node: np.ndarray       # rigid bodies only
    body_aft_node: np.ndarray
    bp: np.ndarray
    btab_n: np.ndarray
    btab: np.ndarray
    pb_mass: np.ndarray         # point bodies, per node
    pb_vol: np.ndarray
    pb_cda: np.ndarray
    pb_ca: np.ndarray
    # environment
    rho: float
    g: float
    cur_z: np.ndarray
    cur_v: np.ndarray
    lines: list[LineMap] = field(default_factory=list)
    bodies: list[BodyMap] = field(default_factory=list)
    anchors: dict = field(default_factory=dict)          # node -> fixed position
    comp_node: int = -1                                   # heave-compensator sheave node, -1 if none
    # series tows (a body towing a tail from its aft tow point): "monolithic" solves the tail's top segments in
    # the body's tow-point clique of the tension tree (their pull acts on the body inside the tension solve),
    # "relaxed" treats that pull as a load inside the Newton loop (block Gauss–Seidel, relaxed). Scene field
    # solver.series_coupling; see tension_cliques
    series_coupling: str = "monolithic"

    def __post_init__(self):
        (self.tn_nseg, self.tn_segs, self.tn_sgn, self.tseg_up,
         self.tseg_uplocal) = tension_cliques(self.node_nseg, self.node_segs, self.node_sgn, self.seg_up,
                                              self.seg_uplocal, self.body_node, self.body_aft_node,
                                              self.series_coupling == "monolithic")

    @property
    def cable_top_node(self) -> int:
        """The node where the cable meets the vessel: the compensator sheave, or the tow point."""
        return self.comp_node if self.comp_node >= 0 else self.top_node

    @property
    def n_nodes(self) -> int:
        return int(self.node_kind.shape[0])

    @property
    def n_segments(self) -> int:
        return int(self.l0.shape[0])

    @property
    def n_rigid(self) -> int:
        return int(self.body_node.shape[0])

    def topo(self) -> Topology:
        return Topology(self.seg_lo, self.seg_up, self.seg_uplocal, self.node_kind, self.node_nseg, self.node_segs,
                        self.node_sgn, self.order, self.pos, self.body_node, self.body_aft_node, self.tn_nseg,
                        self.tn_segs, self.tn_sgn, self.tseg_up, self.tseg_uplocal)

    def segp(self) -> Segments:
        return Segments(self.l0, self.diam, self.mu, self.cn, self.ct, self.can, self.cat, self.ea)

    def bodyp(self) -> Bodies:
        return Bodies(self.bp, self.btab_n, self.btab, self.pb_mass, self.pb_vol, self.pb_cda, self.pb_ca)

    def env(self) -> Water:
        return Water(float(self.rho), float(self.g), self.cur_z, self.cur_v)

    def line(self, name: str) -> LineMap:
        for lm in self.lines:
            if lm.name == name:
                return lm
        raise KeyError(f"no line named {name!r}; lines: {[lm.name for lm in self.lines]}")

    def body(self, name: str) -> BodyMap:
        for bm in self.bodies:
            if bm.name == name:
                return bm
        raise KeyError(f"no body named {name!r}; bodies: {[bm.name for bm in self.bodies]}")


def mirrored_table(inc, cd, cl, cm):
    """Mirror a table given for incidence ≥ 0: drag even, lift and moment odd about their value at 0."""
    inc = np.asarray(inc, float)
    cd, cl, cm = (np.asarray(x, float) for x in (cd, cl, cm))
    if inc[0] != 0.0 or len(inc) < 2:
        return inc, cd, cl, cm
    inc2 = np.concatenate([-inc[:0:-1], inc])
    cd2 = np.concatenate([cd[:0:-1], cd])
    cl2 = np.concatenate([2 * cl[0] - cl[:0:-1], cl])
    cm2 = np.concatenate([2 * cm[0] - cm[:0:-1], cm])
    return inc2, cd2, cl2, cm2


def _slope_at_zero(inc, cl):
    i = int(np.argmin(np.abs(inc)))
    j = i + 1 if i + 1 < len(inc) else i - 1
    if j < 0 or inc[j] == inc[i]:
        return 0.0
    return abs((cl[j] - cl[i]) / np.radians(inc[j] - inc[i]))


from ..scene import scene_field as _get  # noqa: E402  (the one scene accessor; defaults are the schema's)


def _attachment(end):
    """Normalise a line end: returns ('vessel'|'free'|'line'|'splice'|'body'|'anchor', name, distance)."""
    if isinstance(end, str):
        return (end, None, None)
    if _get(end, "line") is not None:
        return ("line", _get(end, "line"), float(_get(end, "distance")))
    if _get(end, "splice") is not None:
        return ("splice", _get(end, "splice"), None)
    if _get(end, "body") is not None:
        return ("body", _get(end, "body"), None)
    if _get(end, "anchor") is not None:
        return ("anchor", None, tuple(float(x) for x in _get(end, "anchor")))
    kind = _get(end, "kind") or _get(end, "type")
    if kind in ("vessel", "free"):
        return (kind, None, None)
    raise ValueError(f"unrecognised line end {end!r}")


def _span_segments(nseg, spans):
    if isinstance(nseg, (list, tuple)):
        counts = [int(x) for x in nseg]
        if len(counts) != len(spans):
            raise ValueError(f"segments list has {len(counts)} entries but the line has {len(spans)} spans")
        return counts
    n = int(nseg)
    total = sum(spans)
    counts = [max(1, int(round(n * sp / total))) for sp in spans]
    # fix the total while keeping >= 1 per span
    while sum(counts) > n and max(counts) > 1:
        i = int(np.argmax([c / sp for c, sp in zip(counts, spans)]))
        if counts[i] > 1:
            counts[i] -= 1
        else:
            break
    while sum(counts) < n:
        i = int(np.argmax([sp / c for c, sp in zip(counts, spans)]))
        counts[i] += 1
    return counts


def build_system(scene) -> System:
    """Discretise a validated scene into flat arrays."""
    from ..scene import Scene, load_scene
    if not isinstance(scene, Scene):            # a dict / path / name: validated first, so the schema's
        scene = load_scene(scene)               # defaults are the only ones
    water = scene.water
    rho = float(water.density)
    g = float(water.gravity)
    lines = list(scene.lines)
    bodies = list(scene.bodies)

    # junctions on each line: distance from the line's top end -> list of child line names
    junctions: dict[str, list[float]] = {_get(ln, "name"): [] for ln in lines}
    for ln in lines:
        kind, name, dist = _attachment(_get(ln, "top"))
        if kind == "line":
            junctions[name].append(dist)

    nodes_pos_hint = []      # unused placeholder to keep node creation explicit
    node_kind: list[int] = []

    def new_node(kind=FREE):
        node_kind.append(kind)
        nodes_pos_hint.append(None)
        return len(node_kind) - 1

    top_node = new_node(PRESCRIBED_TOP)
    comp_node = -1
    vessel_node = top_node
    if _get(scene, "compensator") is not None:
        # the cable's top rides on the compensator sheave; the ship tow point is a separate node
        comp_node = new_node(COMPENSATOR)
        vessel_node = comp_node
    seg_lo: list[int] = []
    seg_up: list[int] = []
    seg_prop: list[tuple] = []
    line_maps: dict[str, LineMap] = {}
    junction_node: dict[tuple[str, float], int] = {}
    body_node_of: dict[str, int] = {}
    anchors: dict[int, np.ndarray] = {}
    aft_node_of: dict[str, int] = {}

    # process lines parents-first
    pending = list(lines)
    done: set[str] = set()
    guard = 0
    while pending:
        guard += 1
        if guard > 10000:
            raise ValueError("line topology is not a tree rooted at the vessel")
        ln = pending.pop(0)
        name = _get(ln, "name")
        kind, ref, dist = _attachment(_get(ln, "top"))
        if kind in ("line", "splice") and ref not in done:
            pending.append(ln)
            continue
        if kind == "body" and ref not in body_node_of:
            pending.append(ln)
            continue
        if kind == "vessel":
            top = vessel_node
        elif kind == "line":
            top = junction_node[(ref, dist)]
        elif kind == "splice":
            top = int(line_maps[ref].nodes[-1])       # the spliced line's free bottom node, shared
        elif kind == "body":
            if ref not in aft_node_of:
                aft_node_of[ref] = new_node(PRESCRIBED_AFT)
            top = aft_node_of[ref]
        else:
            raise ValueError(f"lines.{name}.top: cannot be {kind!r}")
        length = float(_get(ln, "length"))
        cuts = sorted(set(junctions[name]))
        bounds = [0.0] + cuts + [length]
        spans = [bounds[i + 1] - bounds[i] for i in range(len(bounds) - 1)]
        counts = (ln.span_segments(cuts) if hasattr(ln, "span_segments")
                  else _span_segments(_get(ln, "segments"), spans))
        props = (float(_get(ln, "diameter")), float(_get(ln, "mass_per_length")), float(_get(ln, "cn")),
                 float(_get(ln, "ct")), float(_get(ln, "can")), float(_get(ln, "cat")),
                 float(_get(ln, "EA")))
        bkind, bref, banchor = _attachment(_get(ln, "bottom"))
        lnodes = [top]
        lsegs = []
        for isp, (sp, cnt) in enumerate(zip(spans, counts)):
            for k in range(cnt):
                last = (isp == len(spans) - 1) and (k == cnt - 1)
                if last and bkind == "body":
                    nd = new_node(FREE)
                    body_node_of[bref] = nd
                elif last and bkind == "anchor":
                    nd = new_node(PRESCRIBED_FIXED)
                    anchors[nd] = np.array(banchor, float)
                else:
                    nd = new_node(FREE)
                seg_up.append(lnodes[-1])
                seg_lo.append(nd)
                seg_prop.append((sp / cnt,) + props)
                lsegs.append(len(seg_lo) - 1)
                lnodes.append(nd)
            if isp < len(spans) - 1:
                junction_node[(name, bounds[isp + 1])] = lnodes[-1]
        line_maps[name] = LineMap(name, np.array(lnodes), np.array(lsegs), length)
        done.add(name)

    nn = len(node_kind)
    ns = len(seg_lo)
    seg_lo_a = np.array(seg_lo, np.int64)
    seg_up_a = np.array(seg_up, np.int64)
    extra_parent = {c: body_node_of[b] for b, c in aft_node_of.items()}
    if comp_node >= 0:
        extra_parent[comp_node] = top_node
    (node_nseg, node_segs, node_sgn, seg_uplocal, node_up_seg, node_parent, post, order,
     pos) = topology_arrays(nn, seg_lo_a, seg_up_a, extra_parent, top_node)

    sp = np.array(seg_prop, float).reshape(ns, 8)
    l0, diam, mu, cn, ct, can, cat, ea = (sp[:, i].copy() for i in range(8))

    # bodies
    pb_mass = np.zeros(nn)
    pb_vol = np.zeros(nn)
    pb_cda = np.zeros(nn)
    pb_ca = np.zeros(nn)
    rigid = [b for b in bodies if _get(b, "kind") in ("fish", "depressor")]
    nb = len(rigid)
    body_node = np.zeros(nb, np.int64)
    body_aft = -np.ones(nb, np.int64)
    bp = np.zeros((nb, BODY_PARAM))
    btab_n = np.zeros((nb, 2), np.int64)
    btab = np.zeros((nb, 8, MAX_TABLE))
    body_maps = []
    ir = 0
    for b in bodies:
        name = _get(b, "name")
        if name not in body_node_of:
            raise ValueError(f"bodies.{name}: not attached to the bottom of any line")
        nd = body_node_of[name]
        kind = _get(b, "kind")
        if kind in ("ball", "clump"):
            pb_mass[nd] += float(_get(b, "mass"))
            pb_vol[nd] += float(b.volume)
            pb_cda[nd] += float(b.drag_area)
            pb_ca[nd] = float(b.added_mass_coefficient)
            body_maps.append(BodyMap(name, kind, nd, -1))
            continue
        body_node[ir] = nd
        if name in aft_node_of:
            body_aft[ir] = aft_node_of[name]
        bp[ir] = _rigid_body_params(b)
        tabs, n = _tables(b)
        btab[ir, :, :] = tabs
        btab_n[ir] = n
        bp[ir, BP_LIFT_SLOPE] = _slope_at_zero(tabs[0, :n[0]], tabs[2, :n[0]])
        body_maps.append(BodyMap(name, kind, nd, ir, int(body_aft[ir])))
        ir += 1

    cur = _get(scene, "current")
    cur_z, cur_v = current_table(cur)

    system = System(seg_lo=seg_lo_a, seg_up=seg_up_a, seg_uplocal=seg_uplocal,
                  node_kind=np.array(node_kind, np.int64), node_nseg=node_nseg, node_segs=node_segs,
                  node_sgn=node_sgn, order=order, pos=pos, node_parent=node_parent, node_up_seg=node_up_seg,
                  post_order=post, top_node=top_node,
                  l0=l0, diam=diam, mu=mu, cn=cn, ct=ct, can=can, cat=cat, ea=ea,
                  body_node=body_node, body_aft_node=body_aft, bp=bp, btab_n=btab_n, btab=btab,
                  pb_mass=pb_mass, pb_vol=pb_vol, pb_cda=pb_cda, pb_ca=pb_ca,
                  rho=rho, g=g, cur_z=cur_z, cur_v=cur_v,
                  lines=[line_maps[_get(ln, "name")] for ln in lines], bodies=body_maps, anchors=anchors,
                  comp_node=comp_node, series_coupling=_series_coupling(scene))
    tail_masses(system)
    return system


def tail_masses(system: "System") -> None:
    """Store in ``bp[b, BP_TAIL_MASS]`` the mass hanging below each body's aft tow point (series tows): cable dry
    mass, clump/ball masses and towed bodies' mass plus their largest added mass; ``inf`` when the tail
    ends at an anchor. Used only to relax the body–tail coupling of the Newton loop
    (``kernels.aft_segment_stiffness``), so an estimate is enough."""
    s = system
    nb = s.body_node.shape[0]
    if nb == 0:
        return
    nn = s.node_kind.shape[0]
    rigid_at = {int(s.body_node[b]): b for b in range(nb)}
    for b in range(nb):
        c = int(s.body_aft_node[b])
        if c < 0:
            s.bp[b, BP_TAIL_MASS] = 0.0
            continue
        inside = np.zeros(nn, bool)
        for a in range(nn):
            x = a
            while x >= 0 and x != c:
                x = int(s.node_parent[x])
            inside[a] = x == c
        if np.any(s.node_kind[inside] == PRESCRIBED_FIXED):
            s.bp[b, BP_TAIL_MASS] = np.inf
            continue
        m = float(np.sum((s.mu * s.l0)[inside[s.seg_up]])) + float(np.sum(s.pb_mass[inside]))
        for a in np.nonzero(inside)[0]:
            r = rigid_at.get(int(a))
            if r is not None:
                m += float(s.bp[r, BP_MASS] + np.max(s.bp[r, BP_ADDED_MASS:BP_ADDED_MASS + 3]))
        s.bp[b, BP_TAIL_MASS] = m


def current_table(cur):
    if cur is None:
        return np.zeros(1), np.zeros((1, 3))
    depths = _get(cur, "depths")
    if depths:
        return (np.asarray(depths, float).copy(), np.asarray(_get(cur, "velocities"), float).reshape(-1, 3).copy())
    vel = _get(cur, "velocity")
    v = np.zeros(3) if vel is None else np.asarray(vel, float)
    return np.zeros(1), v.reshape(1, 3).copy()


def _vec(v):
    return np.asarray(v, float)


def added_mass_about_tow_point(b) -> np.ndarray:
    """The 6×6 added mass of rigid body ``b`` about its tow point (body axes; over surge, sway, heave, roll,
    pitch, yaw). A matrix given about the point r (``added_mass_reference``) is moved with the rigid-body
    velocity transformation: the reference point moves at v + ω × r = v − S(r) ω, so with
    H = [[𝟙, −S(r)], [0, 𝟙]] the kinetic energy ½ νᵣᵀ M_r νᵣ = ½ νᵀ (Hᵀ M_r H) ν and M_tow point = Hᵀ M_r H.
    Without a matrix: diag(added_mass, added_inertia)."""
    M = getattr(b, "added_mass_matrix", None)
    if M is None:
        return np.diag(np.r_[_vec(b.added_mass), _vec(b.added_inertia)])
    M = np.asarray(M, float)
    M = 0.5 * (M + M.T)                      # symmetric to round-off (the schema checks it to 1e-9)
    r = _vec(b.added_mass_reference)
    H = np.eye(6)
    H[:3, 3:] = -np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    return H.T @ M @ H


def _rigid_body_params(b) -> np.ndarray:
    """One row of ``System.bp`` (the column layout is :mod:`towenv.core.layout`)."""
    p = np.zeros(BODY_PARAM)
    p[BP_MASS] = float(b.mass)
    p[BP_VOLUME] = float(b.volume)
    p[BP_AREA] = float(b.reference_area)
    p[BP_LENGTH] = float(b.reference_length)
    p[BP_CG:BP_CG + 3] = _vec(b.cg)
    p[BP_CB:BP_CB + 3] = _vec(b.cb if b.cb is not None else b.cg)              # the schema: cb defaults to cg
    p[BP_INERTIA:BP_INERTIA + 3] = _vec(b.inertia)
    p[BP_ROT_DAMPING:BP_ROT_DAMPING + 3] = _vec(b.rotational_damping)
    p[BP_QUAD_ROT_DAMPING:BP_QUAD_ROT_DAMPING + 3] = _vec(b.quadratic_rotational_damping)
    if getattr(b, "added_mass_matrix", None) is None:
        p[BP_ADDED_MASS:BP_ADDED_MASS + 3] = _vec(b.added_mass)
        p[BP_ADDED_INERTIA:BP_ADDED_INERTIA + 3] = _vec(b.added_inertia)
    else:
        M = added_mass_about_tow_point(b)
        d = np.diag(M).copy()
        p[BP_ADDED_MASS:BP_ADDED_MASS + 3] = d[:3]
        p[BP_ADDED_INERTIA:BP_ADDED_INERTIA + 3] = d[3:]
        np.fill_diagonal(M, 0.0)
        p[BP_ADDED_COUPLING:BP_ADDED_COUPLING + 36] = M.reshape(36)
        p[BP_ADDED_COUPLED] = 1.0 if np.any(M != 0.0) else 0.0
    p[BP_ADDED_CORIOLIS] = 1.0 if getattr(b, "added_mass_coriolis", False) else 0.0
    ext = _vec(getattr(b, "external_force", (0.0, 0.0, 0.0)))
    p[BP_EXTERNAL_FORCE:BP_EXTERNAL_FORCE + 3] = ext
    p[BP_HAS_EXTERNAL] = 1.0 if np.any(ext != 0.0) else 0.0
    p[BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3] = _vec(b.aft_tow_point if b.aft_tow_point is not None else (0.0, 0.0, 0.0))   # none: unused
    p[BP_REDUCED_DOF] = 1.0 if b.dof == "surge_heave_pitch" else 0.0
    return p


def _table_arrays(t):
    return (np.asarray(_get(t, "incidence_deg"), float), np.asarray(_get(t, "drag"), float),
            np.asarray(_get(t, "lift"), float), np.asarray(_get(t, "moment"), float))


def _tables(b):
    vt = mirrored_table(*_table_arrays(_get(b, "coefficients")))
    ht_src = _get(b, "horizontal_coefficients")
    if ht_src is None:
        inc, cd, cl, cm = _table_arrays(_get(b, "coefficients"))
        if _get(b, "kind") == "depressor":
            cl = cl - cl[np.argmin(np.abs(inc))]
        ht = mirrored_table(inc, cd, cl, cm)
    else:
        ht = mirrored_table(*_table_arrays(ht_src))
    out = np.zeros((8, MAX_TABLE))
    n = np.zeros(2, np.int64)
    for j, tab in enumerate((vt, ht)):
        m = len(tab[0])
        if m > MAX_TABLE:
            raise ValueError(f"coefficient tables longer than {MAX_TABLE} rows (after mirroring) are not supported")
        for k in range(4):
            out[4 * j + k, :m] = tab[k]
        n[j] = m
    return out, n


def _series_coupling(scene) -> str:
    return str(_get(_get(scene, "solver"), "series_coupling"))


def tension_cliques(node_nseg, node_segs, node_sgn, seg_up, seg_uplocal, body_node, body_aft, merge: bool):
    """The node lists of the tension tree (``tn_nseg``, ``tn_segs``, ``tn_sgn``) and each segment's upper node
    and slot in it there (``tseg_up``, ``tseg_uplocal``).

    Without series tows, or with ``merge`` False (solver.series_coupling = "relaxed"), they are the cable
    topology's own lists. With ``merge`` (the default, "monolithic"), an aft tow point ``c`` of body ``b`` is
    merged into the body's tow-point node ``a``: the segments hanging from ``c`` join ``a``'s list (after
    ``a``'s own), ``c``'s list is emptied, and their upper node becomes ``a``. The aft point is rigidly
    carried by the body (r_c = r_a + Λᵀ r_aft), so a tail segment's length depends on the tensions through
    the body's tow-point position exactly as a segment at ``a`` would, and its pull moves ``a`` through the
    condensed body (``houbolt.node_local_solve``, transfer matrix H_b). The tree stays a tree: the tail hangs
    from ``a``, and the elimination order (children before parents, ``c``'s parent is ``a``) is unchanged."""
    tn_nseg = node_nseg.copy()
    tn_segs = node_segs.copy()
    tn_sgn = node_sgn.copy()
    tseg_up = np.array(seg_up, np.int64).copy()
    tseg_uplocal = seg_uplocal.copy()
    if not merge:
        return tn_nseg, tn_segs, tn_sgn, tseg_up, tseg_uplocal
    for b in range(len(body_node)):
        c = int(body_aft[b])
        if c < 0:
            continue
        a = int(body_node[b])
        for k in range(int(node_nseg[c])):
            s = int(node_segs[c, k])
            j = int(tn_nseg[a])
            if j >= node_segs.shape[1]:
                raise ValueError(f"more than {node_segs.shape[1]} segments meet at a body's tow point and its aft "
                                 "tow point together (solver.series_coupling = \"monolithic\"); use \"relaxed\"")
            tn_segs[a, j] = s
            tn_sgn[a, j] = node_sgn[c, k]
            tseg_up[s] = a
            tseg_uplocal[s] = j
            tn_nseg[a] += 1
        tn_nseg[c] = 0
        tn_segs[c, :] = -1
        tn_sgn[c, :] = 0.0
    return tn_nseg, tn_segs, tn_sgn, tseg_up, tseg_uplocal


def topology_arrays(nn, seg_lo, seg_up, extra_parent, top_node):
    """Adjacency, elimination order and static-march order of a tree of ``nn`` nodes.

    ``extra_parent`` links nodes that hang from another node without a segment (aft tow points from
    their body, the compensator sheave from the ship tow point)."""
    ns = len(seg_lo)
    node_nseg = np.zeros(nn, np.int64)
    node_segs = -np.ones((nn, MAX_SEGS_PER_NODE), np.int64)
    node_sgn = np.zeros((nn, MAX_SEGS_PER_NODE), np.float64)
    seg_uplocal = np.zeros(ns, np.int64)
    for s in range(ns):
        for a, sg in ((seg_lo[s], 1.0), (seg_up[s], -1.0)):
            k = node_nseg[a]
            if k >= MAX_SEGS_PER_NODE:
                raise ValueError(f"more than {MAX_SEGS_PER_NODE} segments meet at one node")
            node_segs[a, k] = s
            node_sgn[a, k] = sg
            if sg < 0:
                seg_uplocal[s] = k
            node_nseg[a] += 1
    node_up_seg = -np.ones(nn, np.int64)
    for s in range(ns):
        node_up_seg[seg_lo[s]] = s
    node_parent = -np.ones(nn, np.int64)
    for a in range(nn):
        if node_up_seg[a] >= 0:
            node_parent[a] = seg_up[node_up_seg[a]]
    for c, p in extra_parent.items():
        node_parent[c] = p
    # post-order (children first) from the top node
    children: list[list[int]] = [[] for _ in range(nn)]
    for a in range(nn):
        if node_parent[a] >= 0:
            children[node_parent[a]].append(a)
    post: list[int] = []
    stack = [(top_node, 0)]
    while stack:
        a, state = stack.pop()
        if state == 0:
            stack.append((a, 1))
            for c in children[a]:
                stack.append((c, 0))
        else:
            post.append(a)
    if len(post) != nn:
        raise ValueError("line topology is not connected to the vessel")
    order = np.array([node_up_seg[a] for a in post if node_up_seg[a] >= 0], np.int64)
    pos = np.empty(ns, np.int64)
    pos[order] = np.arange(ns)
    return (node_nseg, node_segs, node_sgn, seg_uplocal, node_up_seg, node_parent, np.array(post, np.int64),
            order, pos)


def remesh_top(sysm: "System", line: str, insert: bool, l_nom: float):
    """Insert a node ``l_nom`` above the node below the top segment of ``line`` (insert=True), or remove
    the node below the top segment, merging the two top segments (insert=False).

    Returns (new System, node map, segment map, info): ``node map[i]`` is the old index of new node i
    (−1 for the inserted node), likewise for segments; ``info`` gives the inserted/removed node's
    neighbours and the split fraction, for moving the dynamic state across. Total unstretched length,
    hence cable mass, is conserved exactly."""
    lm = sysm.line(line)
    s_top = int(lm.segments[0])
    c0 = int(lm.nodes[0])
    c1 = int(lm.nodes[1])
    nn, ns = sysm.n_nodes, sysm.n_segments
    seg_lo = sysm.seg_lo.tolist()
    seg_up = sysm.seg_up.tolist()
    props = np.stack([sysm.l0, sysm.diam, sysm.mu, sysm.cn, sysm.ct, sysm.can, sysm.cat, sysm.ea], axis=1)
    node_kind = sysm.node_kind.tolist()
    if insert:
        l_top = props[s_top, 0]
        new = nn
        node_kind.append(FREE)
        seg_up[s_top] = new                       # lower part: c1 -> new, length l_nom
        seg_lo.append(new)                        # upper part: new -> c0
        seg_up.append(c0)
        props = np.vstack([props, props[s_top]])
        props[s_top, 0] = l_nom
        props[ns, 0] = l_top - l_nom
        node_map = np.concatenate([np.arange(nn), [-1]])
        seg_map = np.concatenate([np.arange(ns), [-1]])
        info = {"inserted": new, "lower": c1, "upper": c0, "fraction": l_nom / l_top, "split": (s_top, ns)}
        new_lines = {}
        for m in sysm.lines:
            if m.name == line:
                new_lines[m.name] = (np.concatenate([[c0, new], m.nodes[1:]]), np.concatenate([[ns], m.segments]))
            else:
                new_lines[m.name] = (m.nodes.copy(), m.segments.copy())
    else:
        if sysm.node_nseg[c1] != 2 or sysm.node_kind[c1] != FREE or sysm.pb_mass[c1] > 0 \
                or c1 in sysm.body_node.tolist() or len(lm.segments) < 2:
            return None
        s_below = int(lm.segments[1])
        seg_up[s_below] = c0
        props[s_below, 0] += props[s_top, 0]
        keep_n = np.array([i for i in range(nn) if i != c1])
        keep_s = np.array([i for i in range(ns) if i != s_top])
        nmap_old_to_new = -np.ones(nn, np.int64)
        nmap_old_to_new[keep_n] = np.arange(len(keep_n))
        smap_old_to_new = -np.ones(ns, np.int64)
        smap_old_to_new[keep_s] = np.arange(len(keep_s))
        seg_lo = [int(nmap_old_to_new[seg_lo[i]]) for i in keep_s]
        seg_up = [int(nmap_old_to_new[seg_up[i]]) for i in keep_s]
        props = props[keep_s]
        node_kind = [node_kind[i] for i in keep_n]
        node_map, seg_map = keep_n, keep_s
        info = {"removed": c1, "merged": (s_top, s_below)}
        new_lines = {}
        for m in sysm.lines:
            nodes = [int(nmap_old_to_new[x]) for x in m.nodes if x != c1]
            segs = [int(smap_old_to_new[x]) for x in m.segments if x != s_top]
            new_lines[m.name] = (np.array(nodes), np.array(segs))
    # remap node-indexed data
    old_to_new = -np.ones(nn, np.int64)
    for i, o in enumerate(node_map):
        if o >= 0:
            old_to_new[o] = i

    def nn_(x):
        return int(old_to_new[x]) if x >= 0 else -1

    n_new = len(node_kind)
    top_node = nn_(sysm.top_node)
    comp_node = nn_(sysm.comp_node)
    body_node = np.array([nn_(x) for x in sysm.body_node], np.int64)
    body_aft = np.array([nn_(x) for x in sysm.body_aft_node], np.int64)
    extra_parent = {int(body_aft[i]): int(body_node[i]) for i in range(len(body_node)) if body_aft[i] >= 0}
    if comp_node >= 0:
        extra_parent[comp_node] = top_node
    seg_lo_a = np.array(seg_lo, np.int64)
    seg_up_a = np.array(seg_up, np.int64)
    (node_nseg, node_segs, node_sgn, seg_uplocal, node_up_seg, node_parent, post, order,
     pos) = topology_arrays(n_new, seg_lo_a, seg_up_a, extra_parent, top_node)

    def per_node(arr):
        out = np.zeros(n_new)
        for i, o in enumerate(node_map):
            if o >= 0:
                out[i] = arr[o]
        return out

    lines = [LineMap(m.name, new_lines[m.name][0].astype(np.int64), new_lines[m.name][1].astype(np.int64), m.length)
             for m in sysm.lines]
    lines = [LineMap(m.name, m.nodes, m.segments, float(props[m.segments, 0].sum())) for m in lines]
    bodies = [BodyMap(b.name, b.kind, nn_(b.node), b.rigid_index, nn_(b.aft_node)) for b in sysm.bodies]
    new = System(seg_lo=seg_lo_a, seg_up=seg_up_a, seg_uplocal=seg_uplocal,
                 node_kind=np.array(node_kind, np.int64), node_nseg=node_nseg, node_segs=node_segs,
                 node_sgn=node_sgn, order=order, pos=pos, node_parent=node_parent, node_up_seg=node_up_seg,
                 post_order=post, top_node=top_node,
                 l0=props[:, 0].copy(), diam=props[:, 1].copy(), mu=props[:, 2].copy(), cn=props[:, 3].copy(),
                 ct=props[:, 4].copy(), can=props[:, 5].copy(), cat=props[:, 6].copy(), ea=props[:, 7].copy(),
                 body_node=body_node, body_aft_node=body_aft, bp=sysm.bp, btab_n=sysm.btab_n, btab=sysm.btab,
                 pb_mass=per_node(sysm.pb_mass), pb_vol=per_node(sysm.pb_vol), pb_cda=per_node(sysm.pb_cda),
                 pb_ca=per_node(sysm.pb_ca), rho=sysm.rho, g=sysm.g, cur_z=sysm.cur_z, cur_v=sysm.cur_v,
                 lines=lines, bodies=bodies, anchors={nn_(k): v for k, v in sysm.anchors.items()},
                 comp_node=comp_node, series_coupling=sysm.series_coupling)
    new.bp = sysm.bp.copy()
    tail_masses(new)
    return new, np.asarray(node_map), np.asarray(seg_map), info
