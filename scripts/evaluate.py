#!/usr/bin/env python
"""Evaluate a policy and every baseline on the evaluation sea states; write a report.

A thin command line: the code is :mod:`agents.evaluate` (installed with ``pip install ".[rl]"``;
``python -m agents.evaluate`` is the same command). ``--help`` lists the options and examples.
"""
import sys

from towenv.extras import RL_COMMAND_MODULES, require_extra

if __name__ == "__main__":
    require_extra("rl", "evaluate.py", RL_COMMAND_MODULES)
    from agents.evaluate import main
    sys.exit(main())
