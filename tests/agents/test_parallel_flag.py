"""``--parallel`` reaches ``train`` through each trainer's command line (agents.common.add_parallel_flag).

The four ARS / Gauss–Newton trainers share one flag definition; each test below runs the trainer's ``main`` with
``train`` replaced by a stub that records its ``parallel`` argument and stops, so the flag is checked through the
real argument parsing and checks of every command line (the training itself is tested per trainer: the parallel
run equals the serial one bit for bit)."""
from __future__ import annotations

import importlib

import pytest


class _Stop(Exception):
    pass


@pytest.mark.parametrize("module", ["agents.ars", "agents.gn", "agents.ars_compensator", "agents.gn_compensator"])
@pytest.mark.parametrize("flag", [True, False])
def test_parallel_flag_reaches_train(module, flag, monkeypatch, tmp_path):
    mod = importlib.import_module(module)
    seen = {}

    def stub(*args, **kw):
        seen["parallel"] = kw.get("parallel")
        raise _Stop

    monkeypatch.setattr(mod, "train", stub)
    argv = ["--export", str(tmp_path / "policy.npz")] + (["--parallel"] if flag else [])
    with pytest.raises(_Stop):
        mod.main(argv)
    assert seen["parallel"] is flag
    assert not (tmp_path / "policy.npz").exists()
