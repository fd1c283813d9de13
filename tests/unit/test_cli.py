"""The ``towenv`` command line (towenv.cli), its summary (towenv.report) and plots (towenv.plots)."""
import json
import math
import subprocess
import sys

import numpy as np
import pytest

import towenv
from towenv.cli import main, parse_override, parse_value
from towenv.report import summarize

FILES = ["result.npz", "timeseries.csv", "summary.md", "summary.json",
         "side_view.png", "plan_view.png", "body_motion.png", "tensions.png", "psd.png"]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def run20(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "tmp"
    code = main(["simulate", "two_part_tow_1", "--duration", "20", "--out", str(out), "--quiet"])
    return code, out


def _numbers(obj):
    if isinstance(obj, bool):
        return
    if isinstance(obj, (int, float)):
        yield obj
    elif obj is None:
        yield math.nan                      # summarize writes non-finite numbers as null
    elif isinstance(obj, dict):
        for v in obj.values():
            yield from _numbers(v)
    elif isinstance(obj, list):
        for v in obj:
            yield from _numbers(v)


def test_scenes_lists_embedded(capsys):
    assert main(["scenes"]) == 0
    out = capsys.readouterr().out
    assert "two_part_tow_1" in out
    for name in towenv.list_scenes():
        assert name in out


def test_simulate_writes_all_files(run20):
    code, out = run20
    assert code == 0
    for f in FILES:
        assert (out / f).is_file() and (out / f).stat().st_size > 0, f


def test_summary_json_finite(run20):
    _, out = run20
    s = json.loads((out / "summary.json").read_text())
    nums = list(_numbers(s))
    assert nums and all(math.isfinite(x) for x in nums)
    assert set(s["bodies"]) == {"depressor", "fish"}
    fish = s["bodies"]["fish"]
    for k in ("heave", "surge", "sway", "roll", "pitch", "yaw"):
        assert fish["significant_amplitude"][k] >= 0
    assert fish["significant_amplitude"]["heave"] > 0
    assert fish["mean_depth"] > 10
    assert fish["rates"]["pitch"]["unit"] == "deg/s" and fish["rates"]["heave"]["limit"] == 1.0
    assert 0 < s["top_tension"]["min"] <= s["top_tension"]["mean"] <= s["top_tension"]["max"]
    assert s["lines"]["primary"]["max_segment_tension"] > 0
    assert s["solver"]["real_time_factor"] > 0 and s["solver"]["steps"] == 1000
    assert s["discard"] == 12.0            # max(ramp 12 s, 0.25 * 20 s)
    md = (out / "summary.md").read_text()
    assert "| quantity" in md and "fish" in md and "real-time factor" in md


def test_pngs_are_valid_images(run20):
    import matplotlib.image as mpimg
    _, out = run20
    for f in FILES:
        if f.endswith(".png"):
            assert (out / f).read_bytes()[:8] == PNG_MAGIC
            img = mpimg.imread(out / f)
            assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 200
            assert float(np.std(img[..., :3])) > 0.01        # not blank


def test_npz_and_csv_consistent(run20):
    _, out = run20
    res = towenv.Result.load(out / "result.npz")
    header = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    data = np.loadtxt(out / "timeseries.csv", delimiter=",", skiprows=1)
    assert data.shape == (len(res.t), len(header))
    assert header[:5] == ["t", "tow_x", "tow_y", "tow_z", "top_tension"]
    assert "fish_pitch_deg" in header and "secondary_bottom_tension" in header
    assert np.allclose(data[:, header.index("fish_pitch_deg")], np.degrees(res.bodies["fish"]["euler"][:, 1]),
                       rtol=1e-6, atol=1e-6)
    # the summary is reproducible from the saved result
    s = summarize(res, 12.0)
    saved = json.loads((out / "summary.json").read_text())
    assert s["bodies"]["fish"]["significant_amplitude"]["pitch"] == pytest.approx(
        saved["bodies"]["fish"]["significant_amplitude"]["pitch"])


def test_bad_scene_file_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\n[[lines]]\nname = "a"\nlength = -5.0\n')
    assert main(["simulate", str(bad), "--duration", "5", "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert err.startswith("towenv: error:") and "lines[0].length" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_unknown_scene_lists_embedded(tmp_path, capsys):
    assert main(["simulate", "no_such_scene", "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "two_part_tow_1" in err


def test_divergence_exit_2(tmp_path, capsys):
    code = main(["simulate", "two_part_tow_1", "--duration", "2", "--set", "solver.max_strain=1e-7",
                 "--out", str(tmp_path / "o"), "--quiet", "--no-plots"])
    assert code == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if "error" in ln]
    assert len(err) == 1 and "diverged" in err[0]


def test_set_override_changes_result(run20, tmp_path):
    _, base = run20
    out = tmp_path / "slow"
    assert main(["simulate", "two_part_tow_1", "--duration", "20", "--out", str(out), "--quiet", "--no-plots",
                 "--set", "vessel.speed=2.0"]) == 0
    a = towenv.Result.load(base / "result.npz")
    b = towenv.Result.load(out / "result.npz")
    assert b.meta["overrides"] == {"vessel.speed": 2.0}
    assert b.tow_point[-1, 0] == pytest.approx(40.0, abs=2.0)           # 2 m/s for 20 s (+ 1 m excitation)
    assert a.tow_point[-1, 0] == pytest.approx(60.0, abs=2.0)
    assert not np.allclose(a.top_tension, b.top_tension)
    assert not list(out.glob("*.png"))


def test_parse_override_values():
    assert parse_override("vessel.speed=2.5") == ("vessel.speed", 2.5)
    assert parse_override("solver.max_iterations=40") == ("solver.max_iterations", 40)
    assert parse_override("lines[0].segments=[6, 2]") == ("lines[0].segments", [6, 2])
    assert parse_override("vessel.ramp={type = \"none\"}") == ("vessel.ramp", {"type": "none"})
    assert parse_value("true") is True
    assert parse_value('{"a": 1}') == {"a": 1}
    assert parse_value("half_cosine") == "half_cosine"


def test_bad_discard_exit_2(tmp_path, capsys):
    assert main(["simulate", "two_part_tow_1", "--duration", "5", "--discard", "6", "--quiet",
                 "--out", str(tmp_path / "o")]) == 2
    assert "--discard" in capsys.readouterr().err


def test_python_dash_m():
    p = subprocess.run([sys.executable, "-m", "towenv", "scenes"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and "two_part_tow_1" in p.stdout


def test_first_run_announces_the_compilation(tmp_path, monkeypatch, capsys):
    """Issue 15 (first use): with a cold numba cache the CLI says that it compiles, before the progress bar."""
    import towenv
    import towenv.core.run as run
    towenv.Simulator("two_part_tow_1").advance(0.1)      # compiles (or loads) kernels.advance
    assert run.kernels_compiled()
    monkeypatch.setattr(run, "kernels_compiled", lambda: False)
    assert main(["simulate", "two_part_tow_1", "--duration", "0.4", "--out", str(tmp_path / "o"), "--no-plots"]) == 0
    assert "compiling the simulator kernels" in capsys.readouterr().err
    monkeypatch.setattr(run, "kernels_compiled", lambda: True)
    assert main(["simulate", "two_part_tow_1", "--duration", "0.4", "--out", str(tmp_path / "p"), "--no-plots"]) == 0
    assert "compiling" not in capsys.readouterr().err
