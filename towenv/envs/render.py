"""Side-view rendering of a TowEnv (matplotlib, imported lazily; off-screen Agg canvas for rgb_array)."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["SideViewer"]


class SideViewer:
    """x–z side view relative to the tow point: cable shapes (``sim.line_state(name)["positions"]``),
    bodies drawn as bars along their pitch attitude, the wave surface, and a status line.

    The environments' default renderer: a renderer is any callable ``renderer(env) -> frame`` (``None`` in
    ``"human"`` mode), optionally with ``close()`` — pass another one as ``renderer=``."""

    def __init__(self, human: bool = False, fps: int = 10, size=(6.4, 4.0), dpi: int = 100):
        self.human = human
        self.fps = fps
        if human:
            import matplotlib.pyplot as plt
            plt.ion()
            self.fig = plt.figure(figsize=size, dpi=dpi)
            self.canvas = self.fig.canvas
        else:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure
            self.fig = Figure(figsize=size, dpi=dpi)
            self.canvas = FigureCanvasAgg(self.fig)
        self.ax = self.fig.add_subplot(111)
        self._limits = None

    def draw(self, env):
        sim = env.sim
        ax = self.ax
        ax.clear()
        top = sim.hist_r[0, sim.system.top_node].copy()
        xs_all, zs_all = [0.0], [top[2]]
        for ln in sim.scene.lines:
            p = sim.line_state(ln.name)["positions"]
            ax.plot(p[:, 0] - top[0], p[:, 2], "-", lw=1.2, marker=".", ms=3, label=ln.name)
            xs_all += list(p[:, 0] - top[0])
            zs_all += list(p[:, 2])
        for b in sim.scene.bodies:
            st = sim.body_state(b.name)
            x, z = st["position"][0] - top[0], st["position"][2]
            pitch = float(st["euler"][1])               # + nose down
            half = 0.5 * float(getattr(b, "reference_length", 1.0) or 1.0) * 3.0   # exaggerated 3x
            dx, dz = half * math.cos(pitch), -half * math.sin(pitch)
            ax.plot([x - dx, x + dx], [z - dz, z + dz], "-", lw=4, solid_capstyle="round")
            ax.annotate(b.name, (x, z), textcoords="offset points", xytext=(4, 6), fontsize=7)
        if self._limits is None:
            x0, x1 = min(xs_all) - 10.0, max(xs_all) + 15.0
            z0, z1 = min(zs_all) - 10.0, 8.0
            self._limits = (x0, x1, z0, z1)
        x0, x1, z0, z1 = self._limits
        if sim.wave is not None:
            xx = np.linspace(x0, x1, 120) + top[0]
            h0 = float(getattr(sim.path, "initial_heading", 0.0))
            eta = np.asarray(sim.wave.elevation(np.full(xx.size, sim.t), math.cos(h0) * xx, -math.sin(h0) * xx))
            eta = eta * float(sim.path.ramp(np.array([sim.t]))[0])
            ax.plot(xx - top[0], eta, "-", color="tab:blue", lw=0.8, alpha=0.7)
        else:
            ax.axhline(0.0, color="tab:blue", lw=0.8, alpha=0.7)
        ax.plot([0.0], [top[2]], "kv", ms=6)
        ax.set_xlim(x0, x1)
        ax.set_ylim(z0, z1)
        ax.set_xlabel("x relative to the tow point (m)")
        ax.set_ylabel("z (m)")
        m = env._last_m or {}
        sea = env.sea[0] if env.sea else None
        title = f"t = {sim.t:6.1f} s"
        if sea is not None:
            title += f"   Hs {sea.hs:.2f} m  Tp {sea.tp:.1f} s  heading {sea.heading_deg:.0f}°"
        if m:
            title += (f"\nheave {m.get('fish_heave', 0.0):+.2f} m  pitch {math.degrees(m.get('fish_pitch', 0.0)):+.1f}°"
                      f"  top tension {m.get('top_tension', 0.0) / 1e3:.2f} kN")
        ax.set_title(title, fontsize=8)
        ax.legend(loc="lower right", fontsize=7)
        ax.grid(True, alpha=0.3)
        self.canvas.draw()
        if self.human:
            import matplotlib.pyplot as plt
            plt.pause(1.0 / max(self.fps, 1))
            return None
        buf = np.asarray(self.canvas.buffer_rgba())
        return np.ascontiguousarray(buf[..., :3])

    __call__ = draw

    def close(self):
        if self.human:
            import matplotlib.pyplot as plt
            plt.close(self.fig)
        self.fig = None
