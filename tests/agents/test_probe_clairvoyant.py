"""scripts/probe_clairvoyant_iterations.py: the clairvoyant winch's first (preview-tracking) plan, its learned plan
and the causal along-cable law, scored on the same episode."""
from __future__ import annotations

import pytest

pytest.importorskip("gymnasium")

import towenv  # noqa: E402,F401
from helpers import load_script  # noqa: E402


@pytest.mark.slow
def test_probe_scores_preview_learned_and_causal_on_one_episode(tmp_path, monkeypatch, capsys):
    """One code-4 entry, 100 s, one learning iteration: every controller removes heave (σ below the no-control
    run's), the learned plan is never worse than the preview plan it starts from (the planner keeps only
    improvements), and out-of-range entries or lengths are refused with exit 2."""
    monkeypatch.chdir(tmp_path)
    probe = load_script("probe_clairvoyant_iterations")
    (row,) = probe.main(["4", "--iterations", "1", "--episode-seconds", "100"])
    entry, label, heading, none, preview, learned, along = row
    assert entry == 4 and "WMO 4" in label
    assert max(preview, learned, along) < none
    assert learned <= preview
    assert "pooled compensation ratio" in capsys.readouterr().out
    for bad in (["12"], ["4", "--episode-seconds", "50"], ["4", "--iterations", "0"]):
        with pytest.raises(SystemExit) as ex:
            probe.main(bad)
        assert ex.value.code == 2
