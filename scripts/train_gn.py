"""Gauss-Newton policy search for the WinchPayout linear residual (agents/gn.py). The recipe of the committed policies:

    python scripts/train_gn.py --seed 0 --iterations 10 --export agents/trained/gn_WinchPayout-v0_s0.npz
"""
from agents.gn import main

if __name__ == "__main__":
    raise SystemExit(main())
