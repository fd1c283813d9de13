"""The linearisation of :class:`towenv.linear.model.LinearModel` about the steady tow: degrees of freedom,
generalised forces of the nonlinear model, the polished statics, the mass, stiffness and forcing matrices
(``M``, ``K = −∂Q/∂q`` by central differences, ``M_u``, ``K_u``), the drag elements handed to the equivalent
linearisation and the node-tree groups of the block solve (formulas: the module docstring of
:mod:`towenv.linear.model`, docs/linear.md)."""
from __future__ import annotations

import numpy as np

from ..core import kernels as K
from ..core.layout import BP_AFT_TOW_POINT, BP_CB


class LinearisationError(ValueError):
    """The scene cannot be linearised (slack static state, winch, rigid segments ...) or the equivalent
    linearisation did not converge. The message names the element and the reason."""


class Linearisation:
    """Mixin of :class:`~towenv.linear.model.LinearModel`: everything computed once, in its constructor."""

    # ---- degrees of freedom ---------------------------------------------------------------------
    def _setup_dofs(self):
        s = self.system
        nn = s.n_nodes
        self.node_dof = -np.ones(nn, np.int64)
        k = 0
        for a in range(nn):
            if s.node_kind[a] == K.FREE:
                self.node_dof[a] = k
                k += 3
        self.ang_dof = np.arange(k, k + 3 * s.n_rigid).reshape(-1, 3) if s.n_rigid else np.zeros((0, 3), np.int64)
        k += 3 * s.n_rigid
        self.n_base = k            # without the stroke
        self.z_dof = k             # stroke, used only when a compensator is active
        self.aft = {int(s.body_aft_node[b]): b for b in range(s.n_rigid) if s.body_aft_node[b] >= 0}

    def _positions(self, q, u):
        """Node positions and Euler angles for generalised coordinates q (length n_base or n_base + 1)."""
        s = self.system
        r = self.r0.copy()
        free = self.node_dof >= 0
        idx = self.node_dof[free]
        r[free] += np.stack([q[idx], q[idx + 1], q[idx + 2]], axis=1)
        ang = self.ang0 + (q[self.ang_dof] if s.n_rigid else 0.0)
        r[s.top_node] += u
        if self.sheave != s.top_node:
            r[self.sheave] = self.r0[self.sheave] + u
        if len(q) > self.n_base:
            r[self.sheave, 2] += q[self.z_dof]
        lam = np.empty((3, 3))
        for c, b in self.aft.items():
            K.rotation_matrix(ang[b, 0], ang[b, 1], ang[b, 2], lam)
            r[c] = r[s.body_node[b]] + lam.T @ s.bp[b, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3]
        return r, ang

    # ---- cable loads of the nonlinear model -------------------------------------------------------
    def _cable_loads(self, r, v):
        """The kernels' segment loads and node assembly at positions ``r`` and velocities ``v``: (tangents,
        stretched lengths, node mass matrices, node forces)."""
        s = self.system
        ns, nn = s.n_segments, s.n_nodes
        tang = np.empty((ns, 3))
        stre = np.empty(ns)
        drag = np.empty((ns, 2, 3))
        bmat = np.empty((ns, 2, 3, 3))
        madd = np.empty((ns, 3, 3))
        mnode = np.empty((nn, 3, 3))
        bnode = np.empty((nn, 3, 3))
        fnode = np.empty((nn, 3))
        K.segment_loads(r, v, s.seg_lo, s.seg_up, s.l0, s.diam, s.mu, s.cn, s.ct, s.can, s.cat, s.rho, s.g,
                        s.cur_z, s.cur_v, tang, stre, drag, bmat, madd)
        K.node_assembly(r, v, s.node_kind, s.node_nseg, s.node_segs, s.node_sgn, s.l0, s.diam, s.mu, s.rho, s.g,
                        drag, bmat, madd, s.pb_mass, s.pb_vol, s.pb_cda, s.pb_ca, s.cur_z, s.cur_v, mnode, bnode,
                        fnode)
        return tang, stre, mnode, fnode

    # ---- nonlinear generalised forces (steady velocities) ---------------------------------------
    def _forces(self, q, u, with_stroke=False):
        """Return (Q (n), segment tensions (S), top reaction (3)) at the steady tow velocity."""
        s = self.system
        r, ang = self._positions(q, u)
        nn = s.n_nodes
        v = np.tile(self.U, (nn, 1))
        tang, stre, mnode, fnode = self._cable_loads(r, v)
        T = s.ea * (stre / s.l0 - 1.0)
        F = fnode.copy()
        np.add.at(F, s.seg_lo, T[:, None] * tang)
        np.add.at(F, s.seg_up, -T[:, None] * tang)
        n = self.n_base + (1 if with_stroke else 0)
        Q = np.zeros(n)
        free = self.node_dof >= 0
        idx = self.node_dof[free]
        Ff = F[free]
        Q[idx] = Ff[:, 0]
        Q[idx + 1] = Ff[:, 1]
        Q[idx + 2] = Ff[:, 2]
        lam = np.empty((3, 3))
        E = np.empty((3, 3))
        fb = np.empty(3)
        mb = np.empty(3)
        bd = np.empty(1)
        cur = np.empty(3)
        w0 = np.zeros(3)
        for b in range(s.n_rigid):
            a = int(s.body_node[b])
            K.rotation_matrix(ang[b, 0], ang[b, 1], ang[b, 2], lam)
            _euler_matrix(ang[b], E)
            vb = lam @ v[a]
            zc = r[a, 2] + lam[0, 2] * s.bp[b, BP_CB] + lam[1, 2] * s.bp[b, BP_CB + 1] + lam[2, 2] * s.bp[b, BP_CB + 2]
            K.current_at(zc, s.cur_z, s.cur_v, cur)
            K.body_loads(b, lam, vb, w0, s.bp, s.btab_n, s.btab, s.rho, s.g, cur, fb, mb, bd)
            i = self.node_dof[a]
            Q[i:i + 3] += lam.T @ fb
            Q[self.ang_dof[b]] += E.T @ mb
        for c, b in self.aft.items():
            a = int(s.body_node[b])
            i = self.node_dof[a]
            Q[i:i + 3] += F[c]
            Jc = self._aft_jacobian(b, ang[b])
            Q[self.ang_dof[b]] += Jc.T @ F[c]
        if with_stroke:
            Q[self.z_dof] = F[self.sheave, 2]
        return Q, T, F[self.sheave].copy()

    def _aft_jacobian(self, b, ang):
        s = self.system
        lam = np.empty((3, 3))
        J = np.empty((3, 3))
        h = 1e-6
        rt = s.bp[b, BP_AFT_TOW_POINT:BP_AFT_TOW_POINT + 3]
        for j in range(3):
            a1 = ang.copy()
            a1[j] += h
            K.rotation_matrix(a1[0], a1[1], a1[2], lam)
            p = lam.T @ rt
            a1[j] -= 2 * h
            K.rotation_matrix(a1[0], a1[1], a1[2], lam)
            J[:, j] = (p - lam.T @ rt) / (2 * h)
        return J

    def _polish_statics(self):
        """Newton iterations on Q(q) = 0 so the linearisation point is an exact equilibrium of the discrete
        dynamic model (the simulator's quasi-static march is consistent to O(segment drag) only)."""
        s = self.system
        q = np.zeros(self.n_base)
        u = np.zeros(3)
        scale = None
        for it in range(30):
            Q, T, _ = self._forces(q, u)
            if scale is None:
                scale = max(float(np.max(np.abs(T))), 1.0)
            res = float(np.max(np.abs(Q))) if len(Q) else 0.0
            if res < 1e-9 * scale:
                break
            Kq = self._fd_stiffness(q, u)[0]
            try:
                dq = np.linalg.solve(Kq, Q)
            except np.linalg.LinAlgError as exc:
                raise LinearisationError(f"statics: singular stiffness at the static state ({exc}); a free "
                                         "node or body has no restoring force") from None
            step = 1.0
            big = np.max(np.abs(dq)) if len(dq) else 0.0
            if big > 0.2 * float(np.min(s.l0)):
                step = 0.2 * float(np.min(s.l0)) / big
            q = q + step * dq
        else:
            raise LinearisationError(f"statics: the Newton polish of the static state did not converge "
                                     f"(max residual force {res:.3g} N)")
        self.static_residual = res
        r, ang = self._positions(q, u)
        self.r0 = r
        self.ang0 = ang
        _, T, F = self._forces(np.zeros(self.n_base), u)
        self.T0 = T
        self.F0_top = F
        tmax = float(np.max(T))
        for k in range(s.n_segments):
            if not T[k] > 1e-6 * tmax:
                raise LinearisationError(f"{self._seg_name(k)} is slack at the static state (T = {T[k]:.3g} N): "
                                         "the linear model needs a taut cable (snap loads are not linear)")

    def _seg_name(self, k):
        for lm in self.system.lines:
            if k in lm.segments:
                return f"segment {int(np.where(lm.segments == k)[0][0])} of line {lm.name!r}"
        return f"segment {k}"

    def _fd_stiffness(self, q, u, with_stroke=False):
        """Central differences of (Q, T, F_top) with respect to q and u."""
        n = len(q) + (1 if with_stroke else 0)
        qq = np.concatenate([q, [0.0]]) if with_stroke else q
        Kq = np.empty((n, n))
        Ku = np.empty((n, 3))
        ns = self.system.n_segments
        Tq = np.empty((ns, n))
        Tu = np.empty((ns, 3))
        Fq = np.empty((3, n))
        Fu = np.empty((3, 3))
        for j in range(n + 3):
            is_ang = j < n and j < self.n_base and j >= self.ang_dof.min(initial=n) and self.system.n_rigid > 0
            h = 1e-6 if is_ang else 1e-5
            outs = []
            for sg in (1.0, -1.0):
                q1 = qq.copy()
                u1 = u.copy()
                if j < n:
                    q1[j] += sg * h
                else:
                    u1[j - n] += sg * h
                outs.append(self._forces(q1, u1, with_stroke))
            dQ = -(outs[0][0] - outs[1][0]) / (2 * h)
            dT = (outs[0][1] - outs[1][1]) / (2 * h)
            dF = (outs[0][2] - outs[1][2]) / (2 * h)
            if j < n:
                Kq[:, j], Tq[:, j], Fq[:, j] = dQ, dT, dF
            else:
                Ku[:, j - n], Tu[:, j - n], Fu[:, j - n] = dQ, dT, dF
        return Kq, Ku, Tq, Tu, Fq, Fu

    # ---- linear matrices --------------------------------------------------------------------------
    def _linearise(self):
        s = self.system
        nb = self.n_base
        q0 = np.zeros(nb)
        u0 = np.zeros(3)
        # stiffness and forcing with the stroke DOF included (dropped when locked)
        self.Kq, self.Ku, self.Tq, self.Tu, self.Fq, self.Fu = self._fd_stiffness(q0, u0, with_stroke=True)
        # kinematic maps P = ∂r/∂q, S = ∂r/∂u (3N x n) at the static state (see _positions)
        n = nb + 1
        nn = s.n_nodes
        P = np.zeros((3 * nn, n))
        Sm = np.zeros((3 * nn, 3))
        for a in range(nn):
            d = self.node_dof[a]
            if d >= 0:
                P[3 * a:3 * a + 3, d:d + 3] = np.eye(3)
        Sm[3 * s.top_node:3 * s.top_node + 3] = np.eye(3)
        Sm[3 * self.sheave:3 * self.sheave + 3] = np.eye(3)
        P[3 * self.sheave + 2, self.z_dof] = 1.0
        for c, b in self.aft.items():
            a = int(s.body_node[b])
            P[3 * c:3 * c + 3] = P[3 * a:3 * a + 3]
            P[3 * c:3 * c + 3, self.ang_dof[b]] = self._aft_jacobian(b, self.ang0[b])
        self.P, self.S = P, Sm
        # mass: node masses (dry + added) at the static state, bodies, projected
        r = self.r0
        v = np.tile(self.U, (nn, 1))
        tang, stre, mnode, fnode = self._cable_loads(r, v)
        self.tang0 = tang.copy()
        self.mnode = mnode.copy()
        Mall = np.zeros((3 * nn, 3 * nn))
        for a in range(nn):
            Mall[3 * a:3 * a + 3, 3 * a:3 * a + 3] = mnode[a]
        Mq = P.T @ Mall @ P
        Mu = P.T @ Mall @ Sm
        self.E0 = np.zeros((s.n_rigid, 3, 3))
        self.lam0 = np.zeros((s.n_rigid, 3, 3))
        att, atr, arr = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
        for b in range(s.n_rigid):
            lam = np.empty((3, 3))
            K.rotation_matrix(*self.ang0[b], lam)
            E = np.empty((3, 3))
            _euler_matrix(self.ang0[b], E)
            self.E0[b], self.lam0[b] = E, lam
            K.body_mass_blocks(b, s.bp, att, atr, arr)
            i = self.node_dof[int(s.body_node[b])]
            ia = np.arange(i, i + 3)
            ja = self.ang_dof[b]
            Mq[np.ix_(ia, ia)] += lam.T @ att @ lam
            Mq[np.ix_(ia, ja)] += lam.T @ atr @ E
            Mq[np.ix_(ja, ia)] += E.T @ atr.T @ lam
            Mq[np.ix_(ja, ja)] += E.T @ arr @ E
        self.Mq, self.Mu = Mq, Mu

    def _drag_elements(self):
        s = self.system
        r = self.r0
        cur = np.empty(3)
        ends_node, mean, tang, kn, kt = [], [], [], [], []
        for k in range(s.n_segments):
            for e, nd in ((0, int(s.seg_lo[k])), (1, int(s.seg_up[k]))):
                K.current_at(r[nd, 2], s.cur_z, s.cur_v, cur)
                ends_node.append(nd)
                mean.append(self.U - cur)
                tang.append(self.tang0[k])
                # the node receives half of the end's drag (segment_loads / node_assembly)
                kn.append(0.5 * 0.5 * s.rho * s.cn[k] * s.diam[k] * s.l0[k])
                kt.append(0.5 * 0.5 * s.rho * s.ct[k] * s.diam[k] * s.l0[k])
        self.c_node = np.array(ends_node, np.int64)
        self.c_mean = np.array(mean, float).reshape(-1, 3)
        self.c_tang = np.array(tang, float).reshape(-1, 3)
        self.c_kn = np.array(kn, float)
        self.c_kt = np.array(kt, float)
        pnodes = [a for a in range(s.n_nodes) if s.pb_mass[a] > 0 and s.pb_cda[a] > 0]
        self.p_node = np.array(pnodes, np.int64)
        pm = []
        for a in pnodes:
            K.current_at(r[a, 2], s.cur_z, s.cur_v, cur)
            pm.append(self.U - cur)
        self.p_mean = np.array(pm, float).reshape(-1, 3)
        self.p_kd = np.array([0.5 * s.rho * s.pb_cda[a] for a in pnodes], float)
        # per-node sparse rows of P: dofs and 3 x k block
        self.node_rows = []
        simple, other = [], []
        for a in range(s.n_nodes):
            blk = self.P[3 * a:3 * a + 3]
            cols = np.where(np.any(blk != 0.0, axis=0))[0]
            srow = self.S[3 * a:3 * a + 3]
            self.node_rows.append((cols, blk[:, cols], srow))
            if len(cols) == 3 and np.allclose(blk[:, cols], np.eye(3), rtol=0, atol=1e-8) and not np.any(srow) \
                    and cols[0] < self.n_base:
                simple.append(a)
            elif len(cols) or np.any(srow):
                other.append(a)
        self.simple_nodes = np.array(simple, np.int64)
        self.other_nodes = other
        d0 = self.node_dof[self.simple_nodes] if simple else np.zeros(0, np.int64)
        self._sI = (d0[:, None, None] + np.arange(3)[None, :, None] + np.zeros((1, 1, 3), np.int64))
        self._sJ = (d0[:, None, None] + np.zeros((1, 3, 1), np.int64) + np.arange(3)[None, None, :])

    def _tree_groups(self, n):
        """Groups of coordinates for the block-tree solve (None if the coupling is not a tree)."""
        s = self.system
        groups = []
        body_of_node = {int(s.body_node[b]): b for b in range(s.n_rigid)}
        for a in range(s.n_nodes):
            d = self.node_dof[a]
            if d < 0:
                continue
            g = [d, d + 1, d + 2]
            if a in body_of_node:
                g += list(self.ang_dof[body_of_node[a]])
            groups.append(g)
        if n > self.n_base:
            groups.append([self.z_dof])
        gid = -np.ones(n, np.int64)
        for k, g in enumerate(groups):
            gid[g] = k
        if np.any(gid < 0):
            return None
        pat = (np.abs(self.Kq[:n, :n]) + np.abs(self.Mq[:n, :n])) > 0
        ng = len(groups)
        adj = np.zeros((ng, ng), bool)
        ii, jj = np.nonzero(pat)
        adj[gid[ii], gid[jj]] = True
        np.fill_diagonal(adj, False)
        if not np.array_equal(adj, adj.T) or adj.sum() // 2 != ng - 1:
            return None
        parent = -np.ones(ng, np.int64)
        seen = np.zeros(ng, bool)
        bfs = [0]
        seen[0] = True
        for g in bfs:
            for h in np.nonzero(adj[g])[0]:
                if not seen[h]:
                    seen[h] = True
                    parent[h] = g
                    bfs.append(int(h))
        if not seen.all():
            return None
        smax = max(len(g) for g in groups)
        gd = np.zeros((ng, smax), np.int64)
        for k, g in enumerate(groups):
            gd[k, :len(g)] = g
        return (gd, np.array([len(g) for g in groups], np.int64), parent, np.array(bfs[::-1], np.int64))

    def _pick_fish(self, fish):
        s = self.system
        if fish is not None:
            try:
                return s.body(fish)
            except KeyError as exc:
                raise ValueError(f"fish: {exc.args[0]}") from None
        fishes = [b for b in s.bodies if b.kind == "fish"]
        if fishes:
            return fishes[0]
        rigid = [b for b in s.bodies if b.rigid_index >= 0]
        if rigid:
            return rigid[-1]
        return s.bodies[-1] if s.bodies else None


def _euler_matrix(ang, E):
    """E with ω = E θ̇ (``euler_rates_to_omega``, linear in the rates)."""
    e = np.zeros(3)
    w = np.empty(3)
    for j in range(3):
        e[:] = 0.0
        e[j] = 1.0
        K.euler_rates_to_omega(ang, e, w)
        E[:, j] = w
