#!/usr/bin/env python
"""Train an SB3 agent (PPO or SAC, also TD3/A2C/DDPG) on a towenv environment.

A thin command line: the code is :mod:`agents.train` (installed with ``pip install ".[rl]"``;
``python -m agents.train`` is the same command). ``--help`` lists the options and examples.
"""
import sys

from towenv.extras import RL_COMMAND_MODULES, require_extra

if __name__ == "__main__":
    require_extra("rl", "train.py", RL_COMMAND_MODULES)
    from agents.train import main
    sys.exit(main())
