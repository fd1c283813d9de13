"""Train an ARS linear residual over the skyhook law on towenv/CompensatorGains-v0 (agents/ars_compensator.py).

    python scripts/train_ars_compensator.py --seed 0 --minutes 30 --export runs/ars_CompensatorGains-v0_s0.npz
"""
import sys

from agents.ars_compensator import main

if __name__ == "__main__":
    sys.exit(main())
