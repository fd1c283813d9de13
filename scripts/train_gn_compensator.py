"""Gauss-Newton policy search for the CompensatorGains linear residual over skyhook (agents/gn_compensator.py), from
a committed ARS compensator policy:

    python scripts/train_gn_compensator.py --seed 0 --init agents/trained/ars_CompensatorGains-v0_s0.npz
"""
from agents.gn_compensator import main

if __name__ == "__main__":
    raise SystemExit(main())
