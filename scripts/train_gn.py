"""Gauss-Newton policy search for the WinchPayout linear residual (agents/gn.py). The recipe of the committed policies:

    python scripts/train_gn.py --seed 0 --iterations 10 --export agents/trained/gn_WinchPayout-v0_s0.npz

One BLAS thread unless OPENBLAS_NUM_THREADS/OMP_NUM_THREADS say otherwise: the seeds run side by side on the cores,
and the predictor's matrix products with two OpenBLAS threads per process on two busy cores were 4x slower (spinning
threads; docs/agents.md "The one-hour recipe that meets the goal").
"""
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from agents.gn import main  # noqa: E402  (after the thread setting: OpenBLAS reads it when it loads)

if __name__ == "__main__":
    raise SystemExit(main())
