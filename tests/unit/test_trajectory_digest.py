"""scripts/trajectory_digest.py: ``--solver KEY=VALUE`` reaches every run, and a malformed item is refused."""
import pytest

from helpers import load_script


@pytest.fixture
def digest(monkeypatch):
    mod = load_script("trajectory_digest")
    monkeypatch.setattr(mod, "SCENES", (("two_part_tow_1", 0.05, 2.0),))
    monkeypatch.setattr(mod, "ENVS", ())
    return mod


def test_solver_settings_reach_the_runs(digest, tmp_path, capsys):
    """The same settings give the same file; computing the body derivatives every step instead of every 10th
    (the default) changes the trajectory (within the Newton tolerance, not bit for bit), so the file differs."""
    a, b, c = (str(tmp_path / f"{n}.npz") for n in "abc")
    assert digest.main([a, "--solver", "body_derivative_refresh=1", "--solver", "predictor=quadratic"]) == 0
    assert digest.main([b, "--solver", "body_derivative_refresh=1", "--solver", "predictor=quadratic"]) == 0
    assert digest.main([c]) == 0
    assert digest.compare(a, b) == 0
    assert digest.compare(a, c) == 1


@pytest.mark.parametrize("item", ["bad", "=1"])
def test_a_malformed_solver_item_is_refused(digest, tmp_path, item, capsys):
    with pytest.raises(SystemExit):
        digest.main([str(tmp_path / "x.npz"), "--solver", item])
    assert "--solver: expected KEY=VALUE" in capsys.readouterr().err
