"""The frequency-domain solution of :class:`towenv.linear.model.LinearModel`: the system at a compensator
setting, complex node velocities, the equivalent-linearised drag damping (:mod:`towenv.linear.eqlin`,
harmonic per frequency or stochastic), the block solve and the Anderson-accelerated fixed point on the
damping, and the outputs (formulas: docs/linear.md)."""
from __future__ import annotations

import numpy as np

from . import eqlin
from .linearise import LinearisationError

BODY_OUTPUTS = ("heave", "surge", "sway", "pitch", "roll", "yaw", "tension")


class HarmonicSolution:
    """Mixin of :class:`~towenv.linear.model.LinearModel`: one solve per frequency set and drag mode."""

    # ---- frequency-domain solution ----------------------------------------------------------------
    def _system_for(self, comp):
        nb = self.n_base
        if comp is None:
            sel = np.arange(nb)
        else:
            sel = np.arange(nb + 1)
        Kq = self.Kq[np.ix_(sel, sel)].copy()
        Ku = self.Ku[sel].copy()
        Mq = self.Mq[np.ix_(sel, sel)].copy()
        Mu = self.Mu[sel].copy()
        Cadd = np.zeros((len(sel), len(sel)))
        if comp is not None:
            z = nb
            Kq[z, z] += comp["stiffness"]
            Cadd[z, z] += comp["damping"]
            Mq[z, z] += comp["mass"]
            Mu[z, 2] += comp["mass"]
        return sel, Kq, Ku, Mq, Mu, Cadd

    def _maps(self, sel):
        key = len(sel)
        if getattr(self, "_map_cache", (None,))[0] != key:
            self._map_cache = (key, np.ascontiguousarray(self.P[:, sel].T).astype(complex),
                               np.ascontiguousarray(self.S.T).astype(complex))
        return self._map_cache[1], self._map_cache[2]

    def _node_velocity(self, X, U, omega, sel):
        """Complex node velocity amplitudes (nf, N, 3) and body (velocity, Euler-rate) amplitudes."""
        PT, ST = self._maps(sel)
        x_all = X @ PT + U @ ST                                # (nf, 3N)
        return (1j * omega[:, None] * x_all).reshape(len(omega), -1, 3), x_all

    def _damping(self, mode, Vn, X, omega, sel, Sig=None):
        """Assemble C (nf or 1, n, n) and C_u from the element equivalent damping."""
        s = self.system
        n = len(sel)
        nf = Vn.shape[0] if mode == 0 else 1
        ne = len(self.c_node)
        Cel = np.zeros((nf, ne, 3, 3))
        if mode == 0:
            Vc = np.ascontiguousarray(Vn[:, self.c_node, :])
            eqlin.cable_equivalent(0, self.c_mean, self.c_tang, self.c_kn, self.c_kt, Vc, np.zeros((1, 3, 3)),
                                   self.nphi_cable, self._gx, self._gw, Cel)
        else:
            eqlin.cable_equivalent(1, self.c_mean, self.c_tang, self.c_kn, self.c_kt,
                                   np.zeros((1, 1, 3), complex), np.ascontiguousarray(Sig["cable"]), self.nphi,
                                   self._gx, self._gw, Cel)
        Cn = np.zeros((nf, s.n_nodes, 3, 3))
        np.add.at(Cn, (slice(None), self.c_node), Cel)
        if len(self.p_node):
            Cp = np.zeros((nf, len(self.p_node), 3, 3))
            if mode == 0:
                eqlin.point_equivalent(0, self.p_mean, self.p_kd, np.ascontiguousarray(Vn[:, self.p_node, :]),
                                       np.zeros((1, 3, 3)), self.nphi, self._gx, self._gw, Cp)
            else:
                eqlin.point_equivalent(1, self.p_mean, self.p_kd, np.zeros((1, 1, 3), complex),
                                       np.ascontiguousarray(Sig["point"]), self.nphi, self._gx, self._gw, Cp)
            np.add.at(Cn, (slice(None), self.p_node), Cp)
        C = np.zeros((nf, n, n))
        Cu = np.zeros((nf, n, 3))
        pos = -np.ones(self.n_base + 1, np.int64)
        pos[sel] = np.arange(n)
        if len(self.simple_nodes):
            C[:, self._sI, self._sJ] += Cn[:, self.simple_nodes]
        for a in self.other_nodes:
            cols, blk, srow = self.node_rows[a]
            cols_ok = pos[cols] >= 0
            cl = pos[cols[cols_ok]]
            bk = blk[:, cols_ok]
            if len(cl) == 0 or not np.any(Cn[:, a]):
                continue
            Ca = Cn[:, a]
            C[:, cl[:, None], cl[None, :]] += np.einsum("ik,fij,jl->fkl", bk, Ca, bk)
            Cu[:, cl, :] += np.einsum("ik,fij,jl->fkl", bk, Ca, srow)
        # rigid bodies
        for b in range(s.n_rigid):
            a = int(s.body_node[b])
            i = self.node_dof[a]
            dofs = np.concatenate([np.arange(i, i + 3), self.ang_dof[b]])
            Cb = np.zeros((nf, 6, 6))
            if mode == 0:
                Vb = np.concatenate([Vn[:, a, :], 1j * omega[:, None] * X[:, pos[self.ang_dof[b]]]], axis=1)
                eqlin.body_equivalent(0, b, self.ang0[b], self.E0[b], self.U, self.r0[a, 2], s.bp, s.btab_n, s.btab,
                                      s.rho, s.g, s.cur_z, s.cur_v, np.ascontiguousarray(Vb), np.zeros((6, 6)),
                                      self.nphi, self._gx, self._gw, Cb)
            else:
                eqlin.body_equivalent(1, b, self.ang0[b], self.E0[b], self.U, self.r0[a, 2], s.bp, s.btab_n, s.btab,
                                      s.rho, s.g, s.cur_z, s.cur_v, np.zeros((1, 6), complex),
                                      np.ascontiguousarray(Sig["body"][b]), self.nphi, self._gx, self._gw, Cb)
            d = pos[dofs]
            C[:, d[:, None], d[None, :]] += Cb
        return C, Cu, Cn

    def _solve(self, omega, Utop, Kq, Ku, Mq, Mu, C, Cu, Cadd):
        w = omega[:, None, None]
        B = Ku[None] - w ** 2 * Mu[None] + 1j * w * Cu
        rhs = -np.einsum("fij,fj->fi", B, Utop)
        tree = self._tree.get(len(Kq)) if self.use_tree else None
        if tree is not None:
            X = np.empty(rhs.shape, complex)
            ok = eqlin.tree_solve(omega, Kq, Mq, np.ascontiguousarray(C), Cadd, rhs, *tree, X)
            if not ok:
                raise LinearisationError("the linear system is singular at some frequency (an undamped mode "
                                         "exactly at an excitation frequency)")
        else:
            A = Kq[None] - w ** 2 * Mq[None] + 1j * w * (C + Cadd[None])
            try:
                X = np.ascontiguousarray(np.linalg.solve(A, rhs[..., None])[..., 0])
            except np.linalg.LinAlgError:
                raise LinearisationError("the linear system is singular at some frequency (an undamped mode "
                                         "exactly at an excitation frequency)") from None
        if not np.all(np.isfinite(X)):
            raise LinearisationError("non-finite response of the linear system")
        return X

    def _iterate_harmonic(self, omega, Utop, comp):
        sel, Kq, Ku, Mq, Mu, Cadd = self._system_for(comp)
        nf, n = len(omega), len(sel)
        # initial guess: every node follows the tow point (quasi-static rigid motion), bodies do not rotate
        X = np.zeros((nf, n), complex)
        Vn = (1j * omega[:, None, None]) * Utop[:, None, :] * np.ones((1, self.system.n_nodes, 1))
        C, Cu, _ = self._damping(0, Vn, X, omega, sel)
        X = self._solve(omega, Utop, Kq, Ku, Mq, Mu, C, Cu, Cadd)
        X, it, rel_f, CN = self._anderson(omega, Utop, X, sel, Kq, Ku, Mq, Mu, Cadd)
        rel = float(np.max(rel_f))
        return sel, X, it, rel, CN

    def _anderson(self, omega, Utop, X, sel, Kq, Ku, Mq, Mu, Cadd, depth: int = 4, beta: float = 0.5):
        """Solve the harmonic fixed point X = G(X) (G: response with the damping C_eq(X)) per frequency.

        Anderson acceleration (type II, depth ``depth``, mixing ``beta``, real coefficients on the real and
        imaginary parts). A frequency whose residual stops decreasing for 3 iterations (or doubles) switches
        to damped iteration on the damping itself, C ← (1 − α) C + α C_eq(X) with α halved whenever the
        change grows: the Anderson step may cycle where the map is non-smooth (a body whose incidence flips
        through ±90°, e.g. the heaving fish at U = 0). Converged when |G(X) − X| ≤ tol |G(X)|."""
        nf, n = X.shape
        m2 = 2 * n
        active = np.ones(nf, bool)
        rel_f = np.full(nf, np.inf)
        best = np.full(nf, np.inf)
        since = np.zeros(nf, np.int64)
        plain = np.zeros(nf, bool)
        alpha = np.full(nf, 0.5)
        last = np.full(nf, np.inf)
        hF = np.zeros((nf, depth + 1, m2))       # ring buffers of residuals and iterates (real form)
        hX = np.zeros((nf, depth + 1, m2))
        cnt = np.zeros(nf, np.int64)
        CN = Cst = Cust = None
        it = 0
        for it in range(1, self.max_iter + 1):
            ia = np.where(active)[0]
            Xa = X[ia]
            Vn, _ = self._node_velocity(Xa, Utop[ia], omega[ia], sel)
            C, Cu, CNa = self._damping(0, Vn, Xa, omega[ia], sel)
            if CN is None:
                CN = np.zeros((nf,) + CNa.shape[1:])
                Cst = np.zeros((nf,) + C.shape[1:])
                Cust = np.zeros((nf,) + Cu.shape[1:])
            pl = plain[ia]
            if pl.any():
                fp = ia[pl]
                al = alpha[fp][:, None, None]
                Cst[fp] = (1 - al) * Cst[fp] + al * C[pl]
                Cust[fp] = (1 - al) * Cust[fp] + al * Cu[pl]
                C[pl], Cu[pl] = Cst[fp], Cust[fp]
            CN[ia] = CNa
            G = self._solve(omega[ia], Utop[ia], Kq, Ku, Mq, Mu, C, Cu, Cadd)
            F = G - Xa
            rel = np.linalg.norm(F, axis=1) / np.maximum(np.linalg.norm(G, axis=1), 1e-300)
            rel_f[ia] = rel
            done = rel < self.tol
            # plain-mode bookkeeping
            grow = pl & (rel > last[ia])
            alpha[ia[grow]] = np.maximum(0.5 * alpha[ia[grow]], 0.02)
            last[ia[pl]] = rel[pl]
            # Anderson-mode stall detection
            am = ~pl & ~done
            better = rel < best[ia]
            since[ia[am & better]] = 0
            since[ia[am & ~better]] += 1
            best[ia] = np.minimum(best[ia], rel)
            stall = am & ((since[ia] >= 3) | (rel > 2.0 * best[ia]))
            if stall.any():
                fs = ia[stall]
                plain[fs] = True
                Cst[fs], Cust[fs] = C[stall], Cu[stall]
            am = am & ~stall
            Xn = G.copy()                            # converged, plain and first Anderson steps: X ← G
            if am.any():
                fa = ia[am]
                fr = np.concatenate([F[am].real, F[am].imag], axis=1)
                xr0 = np.concatenate([Xa[am].real, Xa[am].imag], axis=1)
                slot = cnt[fa] % (depth + 1)
                hF[fa, slot] = fr
                hX[fa, slot] = xr0
                cnt[fa] += 1
                xr = xr0 + beta * fr
                h = np.minimum(cnt[fa], depth + 1)
                use = h >= 2
                if use.any():
                    fu = fa[use]
                    # order the ring buffer oldest → newest, differences of consecutive entries
                    k = np.arange(depth + 1)
                    start = np.where(cnt[fu] > depth + 1, cnt[fu] % (depth + 1), 0)
                    idx = (start[:, None] + k[None, :]) % (depth + 1)
                    Fo = np.take_along_axis(hF[fu], idx[:, :, None], axis=1)
                    Xo = np.take_along_axis(hX[fu], idx[:, :, None], axis=1)
                    dF = np.diff(Fo, axis=1)                      # (m, depth, 2n)
                    dX = np.diff(Xo, axis=1)
                    valid = (k[None, 1:] < h[use][:, None])     # difference j valid if j + 1 < h
                    dF = dF * valid[..., None]
                    dX = dX * valid[..., None]
                    A = np.einsum("mij,mkj->mik", dF, dF)
                    tr = np.trace(A, axis1=1, axis2=2)
                    A = A + (1e-12 * tr[:, None, None] + 1e-300) * np.eye(depth)[None] \
                        + np.eye(depth)[None] * (~valid)[:, :, None] * (1.0 + tr[:, None, None])
                    rhs = np.einsum("mij,mj->mi", dF, fr[use])
                    gam = np.linalg.solve(A, rhs[..., None])[..., 0]
                    xr[use] = xr[use] - np.einsum("mij,mi->mj", dX + beta * dF, gam)
                Xn[am] = xr[:, :n] + 1j * xr[:, n:]
            X[ia] = Xn
            active[ia[done]] = False
            if not active.any():
                break
        return X, it, rel_f, CN

    def _outputs(self, X, U, omega, sel, CN):
        """Complex output amplitudes for responses X (nf, n) to top motions U (nf, 3)."""
        s = self.system
        n = len(sel)
        x_all = (X @ self.P[:, sel].T + U @ self.S.T).reshape(len(omega), -1, 3)
        T = X @ self.Tq[:, sel].T + U @ self.Tu.T
        out = {}
        # top reaction: the simulator's node_reaction at the cable's top node (tension + own loads − inertia)
        ct = self.sheave
        Cn = np.broadcast_to(CN, (len(omega),) + CN.shape[1:])
        xt = x_all[:, ct, :]
        dF = X @ self.Fq[:, sel].T + U @ self.Fu.T
        dF = dF - np.einsum("fij,fj->fi", Cn[:, ct], 1j * omega[:, None] * xt) \
            + (omega ** 2)[:, None] * (xt @ self.mnode[ct].T)
        F0 = self.F0_top
        out["top_tension"] = dF @ F0 / max(np.linalg.norm(F0), 1e-300)
        top_seg = int(s.node_segs[ct, 0])
        out["top_segment_tension"] = T[:, top_seg]
        out["stroke"] = X[:, n - 1] if n > self.n_base else np.zeros(len(omega), complex)
        for bm in s.bodies:
            a = bm.node
            out[f"{bm.name}_surge"] = x_all[:, a, 0]
            out[f"{bm.name}_sway"] = x_all[:, a, 1]
            out[f"{bm.name}_heave"] = x_all[:, a, 2]
            if bm.rigid_index >= 0:
                ad = self.ang_dof[bm.rigid_index]
                out[f"{bm.name}_roll"] = X[:, ad[0]]
                out[f"{bm.name}_pitch"] = X[:, ad[1]]
                out[f"{bm.name}_yaw"] = X[:, ad[2]]
            seg = int(s.node_up_seg[a])
            if seg >= 0:
                out[f"{bm.name}_tension"] = T[:, seg]
        f = self.fish
        if f is not None:
            for k in BODY_OUTPUTS:
                if f"{f.name}_{k}" in out:
                    out[f"fish_{k}"] = out[f"{f.name}_{k}"]
        else:
            bottom = int(s.lines[0].nodes[-1])
            out["fish_surge"], out["fish_sway"], out["fish_heave"] = (x_all[:, bottom, i] for i in range(3))
            out["fish_tension"] = T[:, int(s.lines[0].segments[-1])]
        out["_T"] = T
        return out

    # ---- public API -------------------------------------------------------------------------------------
