"""Gauss-Newton policy search for the WinchPayout linear residual (agents/gn.py). The recipe of the committed policies:

    python scripts/train_gn.py --seed 0 --iterations 10 --export agents/trained/gn_WinchPayout-v0_s0.npz

One BLAS thread unless OPENBLAS_NUM_THREADS or OMP_NUM_THREADS is set (then both are left as the user set them): the
seeds run side by side on the cores, and the predictor's matrix products with two OpenBLAS threads per process on two
busy cores were 4x slower (spinning threads; docs/agents.md "The one-hour recipe that meets the goal"). The policy
file records the two variables (``meta["blas_env"]``): products differ in the last bits between thread counts, so a
training reproduces bit for bit with the same setting (the files before ``gnr`` were trained with two threads:
``OPENBLAS_NUM_THREADS=2``).
"""
import os

BLAS_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")
if not any(v in os.environ for v in BLAS_VARS):
    for _var in BLAS_VARS:
        os.environ[_var] = "1"

from agents.gn import main  # noqa: E402  (after the thread setting: OpenBLAS reads it when it loads)

if __name__ == "__main__":
    raise SystemExit(main())
