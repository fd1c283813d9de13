"""Train an ARS linear residual over the along-cable winch law on towenv/WinchPayout-v0 (agents/ars.py).

    python scripts/train_ars.py --seed 0 --minutes 110 --max-iterations 70    # v2 -> runs/ars2_WinchPayout-v0_s0.npz
"""
import sys

from agents.ars import main

if __name__ == "__main__":
    sys.exit(main())
