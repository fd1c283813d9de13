"""Regenerate ``houbolt_reference.npz``: short Houbolt trajectories stored from the kernel as it was
*before* the moving attitude chart was added (commit 299a4cc, Euler angles only). It was made by running
this script against that code:

    cd <checkout of 299a4cc> && PYTHONPATH=. python <this worktree>/tests/data/make_houbolt_reference.py

Regenerated once since, for a deliberate physics change: the gyroscopic term of the body equations now
includes the added inertia (``condense_body``; docs/validation.md problem 3). The file was made from the
same 299a4cc checkout with that one change applied (the line ``hvec[i] -= bp[b, 23 + i] * w[i]`` deleted
from ``condense_body``), so it is still the pre-chart kernel with today's physics.

Regenerated a second time for the series-tow relaxation (``kernels.aft_segment_stiffness`` /
``aft_rotational_stiffness``, ``system.tail_masses``: the body–tail coupling relaxed inside the Newton
loop, which changes the iterates but not the converged solution): the same 299a4cc checkout with the
gyroscopic change, those functions and their two call sites in ``houbolt_step`` applied. Only
``series_multitow`` changed (by ≤ 4e-12 m in positions, ≤ 5e-9 N in tensions: Newton-tolerance level);
the three scenes without an aft tow point were reproduced bit for bit.

The attitude test (tests/verification/test_attitude.py) checks that the current kernel reproduces the trajectories bit
for bit when no body re-charts (every body's pitch stays below the re-chart threshold in these runs).

Regenerated a third time, with no change to the recipe above, on the machine CI runs on (an AMD EPYC host,
numba 0.68.1): numba compiles for the host CPU, and on another CPU the same code gives results that differ
in the last bits (≤ 2e-14 relative in positions after 300 steps here), so a bit-for-bit comparison is only
meaningful on the machine that made the file. The file therefore records :func:`fingerprint` (host CPU,
numba, llvmlite, numpy, scipy); the test demands bit-identity when the fingerprint matches and round-off
agreement otherwise.

Regenerated a fourth time (2026-12-02, issue 16) when the kernels stopped compiling with fast-math
(``towenv/core/jit.py``: with reassociation allowed, the last bits depended on how LLVM inlined a kernel, and
so on whether it was compiled in the process or loaded from numba's cache). Without fast-math the compiled
arithmetic is exactly the source's, so the recipe must now reproduce two deliberate round-off changes made
since the file was first written, which fast-math had happened to absorb or which no test machine had
checked bit for bit:

* the statics' Morison drag is the kernels' shared helper (issue 16, "one Morison drag"): in the 299a4cc
  checkout, ``statics._segment_drag`` returns ``cable_loads.morison_drag`` (``relative_velocity_parts`` and
  ``morison_force`` copied verbatim, compiled with the checkout's ``njit``) instead of its numpy expression;
* the Simulator's tow-point positions come from the phase-recurrence buffer (issue 15,
  ``towenv.core.tow_point``; ≤ 1e-9 m from the exact sum): the old kernel is fed the current code's tow-point
  positions, exported first from this worktree.

and the 299a4cc checkout's ``_FASTMATH`` set to ``False``. The recipe is therefore two commands::

    python tests/data/make_houbolt_reference.py --export-tow-points /tmp/tow_points.npz
    cd <patched 299a4cc checkout> && PYTHONPATH=. python <this worktree>/tests/data/make_houbolt_reference.py \
        --tow-points /tmp/tow_points.npz

Against the third file: positions ≤ 9.4e-10 m, angles ≤ 4e-11 rad, tensions ≤ 6.1e-6 N (of ~3e4) — round-off
and Newton-tolerance level; the current kernel reproduces the new file bit for bit.

Since the monolithic series coupling became the default (2026-12, issue 18: ``solver.series_coupling``), the test
runs ``series_multitow`` with ``solver.series_coupling = "relaxed"``, the coupling this file was made with (the
299a4cc checkout has no such field, so the override is applied by the test, not in ``CASES``); the monolithic
coupling converges to the same solution (tests/unit/test_series_coupling.py).

Since the adaptive Newton predictor became the default (2026-12-06: ``solver.predictor``), the test also runs every
case with ``solver.predictor = "quadratic"``, the predictor of the 299a4cc kernel.

Do not regenerate it with a changed kernel unless the change is meant to alter the results.
"""
from pathlib import Path

import numpy as np

import towenv

CASES = {
    # scene, overrides, steps
    "two_part_tow_1": ({}, 300),
    "series_multitow": ({}, 200),
    "hover_deep_tow": ({}, 300),
    # validation case 3b, SS6, locked compensator, cg-mapped towfish, seed 1: snap loads; in the first 40 s the
    # towfish pitch stays below the 30° re-chart threshold (the old code stopped at 46.4 s with the ±85° limit)
    "hover_ss6_locked_cg": ({}, 2000),
}


def hover_ss6_locked_cg():
    import tempfile

    from towenv.validation import hover as H
    rao = H._rao_csv(tempfile.mkdtemp(), H.deck_gain())
    return H.cg_mapped(H._comp_scene(rao, 6, "locked", 0.0, 0.0, 40.0, seed=1))


def fingerprint() -> str:
    """What decides the last bits of a compiled run: the host CPU numba compiles for and the library versions."""
    import llvmlite
    import llvmlite.binding as llvm
    import numba
    import scipy
    return (f"cpu {llvm.get_host_cpu_name()}; numba {numba.__version__}; llvmlite {llvmlite.__version__}; "
            f"numpy {np.__version__}; scipy {scipy.__version__}")


def run(scene, overrides, steps):
    sim = towenv.Simulator(hover_ss6_locked_cg() if scene == "hover_ss6_locked_cg" else scene, **overrides)
    sim.advance_steps(steps)
    return sim


def export_tow_points(path):
    """Write the current code's tow-point positions of every case (steps 0 … steps + 4096)."""
    out = {}
    for scene, (ov, steps) in CASES.items():
        sim = towenv.Simulator(hover_ss6_locked_cg() if scene == "hover_ss6_locked_cg" else scene, **ov)
        out[scene] = sim._tow_points(0, steps + 4096)
    np.savez(path, **out)
    print("wrote", path)


def use_tow_points(path):
    """Make the (old) Simulator read its tow-point positions from ``path`` (see the module docstring)."""
    from towenv.core.simulator import Simulator
    stored = np.load(path)
    Simulator._reference_tow_points = None

    def _tow_points(self, first, n):
        return Simulator._reference_tow_points[first:first + n].copy()
    Simulator._tow_points = _tow_points
    return stored


def main():
    import argparse
    ap = argparse.ArgumentParser(description="regenerate houbolt_reference.npz (see the module docstring)")
    ap.add_argument("--export-tow-points", metavar="NPZ")
    ap.add_argument("--tow-points", metavar="NPZ")
    a = ap.parse_args()
    if a.export_tow_points:
        export_tow_points(a.export_tow_points)
        return
    stored = use_tow_points(a.tow_points) if a.tow_points else None
    out = {}
    for scene, (ov, steps) in CASES.items():
        if stored is not None:
            from towenv.core.simulator import Simulator
            Simulator._reference_tow_points = stored[scene]
        sim = run(scene, ov, steps)
        out[f"{scene}::hist_r"] = sim.hist_r.copy()
        out[f"{scene}::hist_ang"] = sim.hist_ang.copy()
        out[f"{scene}::tens_hist"] = sim.tens_hist.copy()
        out[f"{scene}::top_react"] = sim.top_react.copy()
        out[f"{scene}::counters"] = sim.counters.copy()
        out[f"{scene}::steps"] = np.array(steps)
        print(scene, sim.system.n_rigid, "rigid bodies, max |pitch| (deg)",
              np.degrees(np.abs(sim.hist_ang[0, :, 1])).max() if sim.system.n_rigid else None, sim.stats)
    out["fingerprint"] = np.array(fingerprint())
    np.savez_compressed(Path(__file__).with_name("houbolt_reference.npz"), **out)
    print("towenv from", towenv.__file__)


if __name__ == "__main__":
    main()
