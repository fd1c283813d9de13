"""scripts/winch_limit_use.py: the fraction of the scored time at the winch's limits, from the observed winch speed."""
from __future__ import annotations

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import towenv  # noqa: E402,F401
from helpers import load_script  # noqa: E402


def test_fixed_winch_never_reaches_a_limit_and_an_aggressive_law_does(capsys):
    """A winch held still (fixed_winch) is never at a limit; along-cable cancellation in a code-5 sea is at the
    acceleration limit part of the time (the standard winch: 1.5 m/s²) and the fractions are fractions."""
    wl = load_script("winch_limit_use")
    from agents.baselines import make_baseline
    from agents.evaluation import eval_episodes, make_eval_env
    env = make_eval_env("towenv/WinchPayout-v0", {"episode_seconds": 120.0})
    (_k, _l, sea, seed), = eval_episodes(env, 1, [8])
    sp, ac = wl.limit_use(env, make_baseline("fixed_winch", env), sea, seed)
    assert sp == 0.0 and ac == 0.0
    sp, ac = wl.limit_use(env, make_baseline("along_cable", env), sea, seed)
    assert 0.0 <= sp < 0.05 and 0.05 < ac < 1.0
    with pytest.raises(SystemExit):
        wl.main(["along_cable", "--replicates", "0"])
    assert "--replicates" in capsys.readouterr().err
