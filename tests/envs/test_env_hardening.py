"""Issue 17 (hardening), environment items 10–12: step before reset / after the episode ended, action shapes
and types, constructor keywords and reset options — each with a regression test that failed before the fix —
plus hypothesis fuzz tests of constructor keywords, reset options and actions (single and batched envs):
every case ends in a clear error of the documented type naming the field, or in a finite result.

Documented errors (docs/environments.md "Errors and validation"): ``ConfigError`` (a ValueError) for keywords
and reset options, ``ActionError`` (a ValueError) for actions, ``ResetNeeded`` (gymnasium.error.ResetNeeded
and RuntimeError) for stepping without a live episode; unknown keywords raise Python's TypeError."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")
pytest.importorskip("hypothesis")

from hypothesis import HealthCheck, event, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import towenv.envs  # noqa: E402,F401  (registers the ids)
from towenv.envs.checks import ActionError, ConfigError, ResetNeeded  # noqa: E402
from towenv.envs.compensator import CompensatorGainsEnv  # noqa: E402
from towenv.envs.pieces import Limits, PartedOrGrounded  # noqa: E402
from towenv.envs.vector import CompensatorGainsVectorEnv, WinchPayoutVectorEnv  # noqa: E402
from towenv.envs.winch import WinchPayoutEnv  # noqa: E402
from towenv.sea import SeaState  # noqa: E402

CLASSES = (CompensatorGainsEnv, WinchPayoutEnv)
VECTOR = {CompensatorGainsEnv: CompensatorGainsVectorEnv, WinchPayoutEnv: WinchPayoutVectorEnv}
FUZZ = settings(deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))

_ENVS: dict = {}


def _env(cls):
    """One shared environment per class for the fuzz tests that do not change keywords."""
    if cls not in _ENVS:
        _ENVS[cls] = cls(episode_seconds=1.0)
    return _ENVS[cls]


def _finite_step(out):
    obs, r, te, tr, info = out
    assert np.all(np.isfinite(obs)) and math.isfinite(r), (obs, r, info)
    assert all(math.isfinite(v) for v in info["reward_components"].values())
    return te or tr


# ======================================================================================== item 10
@pytest.mark.parametrize("cls", CLASSES)
def test_step_before_reset_raises_reset_needed(cls):
    env = cls()
    with pytest.raises(ResetNeeded, match="before reset"):
        env.step(env.action_space.sample())
    assert issubclass(ResetNeeded, gym.error.ResetNeeded) and issubclass(ResetNeeded, RuntimeError)
    env.reset(seed=0)
    _finite_step(env.step(env.action_space.sample()))


@pytest.mark.parametrize("cls", CLASSES)
def test_step_after_truncation_raises_and_reset_recovers(cls):
    env = cls(episode_seconds=0.3)                       # 3 control steps
    env.reset(seed=0)
    flags = [env.step(env.action_space.sample())[3] for _ in range(3)]
    assert flags == [False, False, True]
    t_end = env.sim.t
    with pytest.raises(ResetNeeded, match="after the episode ended"):
        env.step(env.action_space.sample())
    assert env.sim.t == t_end                            # time did not advance
    env.reset(seed=1)
    assert not env.step(env.action_space.sample())[3]


def test_step_after_termination_raises_instead_of_charging_the_terminal_cost_again():
    env = CompensatorGainsEnv(floor_depth=30.0)          # the fish tows at ~40 m: terminates at once
    env.reset(seed=0)
    _, r, te, _, info = env.step(env.action_space.sample())
    assert te and info["reward_components"]["terminal"] > 0
    with pytest.raises(ResetNeeded):
        env.step(env.action_space.sample())


def test_rejected_or_failed_reset():
    env = WinchPayoutEnv()
    env.reset(seed=0)
    env.step(np.zeros(1, np.float32))
    with pytest.raises(ConfigError, match="sea_seed"):
        env.reset(options={"sea_seed": 3})               # options are checked before anything changes ...
    env.step(np.zeros(1, np.float32))                    # ... so the episode goes on
    with pytest.raises(ConfigError, match="cable_length"):
        env.reset(options={"cable_length": 5.0})          # the junction would lie above the top: fails in reset
    with pytest.raises(ResetNeeded, match="raised"):
        env.step(np.zeros(1, np.float32))
    env.sea_generator = lambda rng: ("calm", 0)          # a broken generator
    with pytest.raises(ConfigError, match="sea_generator"):
        env.reset(seed=0)
    with pytest.raises(ResetNeeded, match="raised"):
        env.step(np.zeros(1, np.float32))


def test_gym_make_and_vector_env_order_enforcement():
    env = gym.make("towenv/WinchPayout-v0")
    with pytest.raises(gym.error.ResetNeeded):
        env.step(env.action_space.sample())
    venv = WinchPayoutVectorEnv(2)
    with pytest.raises(ResetNeeded, match="reset"):
        venv.step(np.zeros((2, 1), np.float32))
    # the batched env keeps auto-resetting finished copies (NEXT_STEP), as SB3 VecEnvs do
    venv = WinchPayoutVectorEnv(2, episode_seconds=0.2)
    venv.reset(seed=0)
    dones = []
    for _ in range(5):
        _, rew, te, tr, _ = venv.step(np.zeros((2, 1), np.float32))
        dones.append(bool((te | tr).all()))
        assert np.all(np.isfinite(rew))
    assert dones == [False, True, False, False, True]


def test_checkers_still_pass():
    from gymnasium.utils.env_checker import check_env
    for env_id in towenv.envs.ENV_IDS:                  # step-before-reset raising is what the checker expects
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check_env(gym.make(env_id, render_mode="rgb_array").unwrapped)


# ======================================================================================== item 11
BAD_ACTIONS_WINCH = [np.zeros((2, 1)), None, ["1"], np.array([1j]), np.array([True]), [0.1, 0.2, 0.3],
                     np.zeros((1, 1)), "0.5", [None], np.zeros(0), {"a": 1}]
BAD_ACTIONS_COMP = [np.zeros((2, 1)), None, ["1", "2"], np.array([1j, 0]), np.array([True, False]), [0.1, 0.2, 0.3],
                    0.5, [[0.1, 0.2]], np.array(["a", "b"])]


@pytest.mark.parametrize("cls, action", [(WinchPayoutEnv, a) for a in BAD_ACTIONS_WINCH]
                         + [(CompensatorGainsEnv, a) for a in BAD_ACTIONS_COMP])
def test_bad_actions_are_refused_naming_the_action_space(cls, action):
    env = _env(cls)
    env.reset(seed=0)
    with pytest.raises(ActionError) as exc:
        env.step(action)
    msg = str(exc.value)
    assert "action space" in msg and repr(env.action_space) in msg
    assert isinstance(exc.value, ValueError)
    _finite_step(env.step(env.action_space.sample()))      # a refused action leaves the episode untouched


@pytest.mark.parametrize("cls, forms", [
    (WinchPayoutEnv, [np.array([0.25], np.float32), [0.25], (0.25,), 0.25, np.float64(0.25), np.array(0.25)]),
    (CompensatorGainsEnv, [np.array([0.5, -0.25], np.float32), [0.5, -0.25], (0.5, -0.25),
                           np.array([0.5, -0.25], np.float16)]),
    (WinchPayoutEnv, [np.array([1.0], np.float32), [1], np.array([1], np.int64), 1]),
])
def test_accepted_action_forms_give_identical_steps(cls, forms):
    results = []
    for a in forms:
        env = cls(episode_seconds=1.0)
        env.reset(seed=3)
        results.append(env.step(a)[:2])
    for obs, r in results[1:]:
        np.testing.assert_array_equal(obs, results[0][0])
        assert r == results[0][1]


@pytest.mark.parametrize("cls", CLASSES)
def test_clipping_and_nan_are_kept_but_warn_once(cls):
    env = cls()
    env.reset(seed=0)
    dim = env.action_space.shape[0]
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        env.step(np.zeros(dim, np.float32))
        assert not w
        env.step(np.full(dim, 5.0))
        env.step(np.full(dim, np.nan))
        env.step(np.full(dim, -np.inf))
    msgs = [str(x.message) for x in w]
    assert len(msgs) == 1 and "clipped" in msgs[0] and "once" in msgs[0], msgs
    # clipping and NaN -> 0 as documented
    ref = cls()
    ref.reset(seed=0)
    env2 = cls()
    env2.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = env2.step(np.array([7.0, np.nan][:dim]))[0]
    b = ref.step(np.array([1.0, 0.0][:dim]))[0]
    np.testing.assert_array_equal(a, b)


def test_vector_env_actions_validated():
    venv = CompensatorGainsVectorEnv(3)
    venv.reset(seed=0)
    for bad in (np.zeros((3, 1)), np.zeros(6), np.zeros((2, 2)), None, np.zeros((3, 2), complex),
                np.zeros((3, 2), bool), [["a", "b"]] * 3):
        with pytest.raises(ActionError, match="action space"):
            venv.step(bad)
    venv.step(np.zeros((3, 2), np.float32))
    venv.step([[0.1, 0.2]] * 3)
    wv = WinchPayoutVectorEnv(2)
    wv.reset(seed=0)
    o1 = wv.step(np.array([0.3, -0.3]))[0]               # (num_envs,) accepted for a one-dimensional action
    w2 = WinchPayoutVectorEnv(2)
    w2.reset(seed=0)
    o2 = w2.step(np.array([[0.3], [-0.3]], np.float32))[0]
    np.testing.assert_array_equal(o1, o2)
    with pytest.raises(ActionError, match=r"\(2, 1\)"):
        wv.step(np.zeros((1, 2)))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        wv.step(np.full((2, 1), 3.0))
        wv.step(np.full((2, 1), np.nan))
    assert len([x for x in w if "clipped" in str(x.message)]) == 1


# ======================================================================================== item 12
class _BadLimits:
    """A termination piece whose ``limits`` are not :class:`~towenv.envs.pieces.Limit` objects."""
    limits = ("tension_ratio >= 1",)

    def __call__(self, m):
        return None


BAD_KWARGS = [
    ({"breaking_load": 0.0}, "breaking_load"), ({"breaking_load": -5.0}, "breaking_load"),
    ({"breaking_load": {"primary": 0.0}}, "breaking_load"), ({"breaking_load": {"tether": 1e5}}, "breaking_load"),
    ({"breaking_load": "strong"}, "breaking_load"), ({"floor_depth": float("nan")}, "floor_depth"),
    ({"floor_depth": -1.0}, "floor_depth"), ({"control_hz": True}, "control_hz"), ({"control_hz": 0.01}, "control_hz"),
    ({"control_hz": float("inf")}, "control_hz"), ({"dt": 2.0}, "dt"), ({"dt": 1e-4}, "dt"),
    ({"episode_seconds": 0}, "episode_seconds"), ({"sea_codes": "345"}, "sea_codes"), ({"sea_codes": ()}, "sea_codes"),
    ({"sea_codes": (3.5,)}, "sea_codes"), ({"sea_codes": (10,)}, "sea_codes"),
    ({"sea_convention": "calm"}, "sea_convention"),
    ({"heading_deg": float("nan")}, "heading_deg"), ({"heading_spread_deg": -1}, "heading_spread_deg"),
    ({"vessel_speeds": (100.0,)}, "vessel_speeds"), ({"vessel_speeds": ()}, "vessel_speeds"),
    ({"cable_lengths": (5.0,)}, "cable_lengths"), ({"cable_lengths": "85"}, "cable_lengths"),
    ({"cable_line": 3}, "cable_line"), ({"observations": "fish_heave"}, "observations"),
    ({"observations": ("nope",)}, "observation"), ({"sensor_noise": {"fish_heave_dev": -1}}, "sensor_noise"),
    ({"sensor_noise": {"fish_heave_dev": "a"}}, "sensor_noise"), ({"obs_delay": float("nan")}, "obs_delay"),
    ({"obs_delay": 1.5}, "obs_delay"), ({"obs_delay": 10 ** 9}, "obs_delay"),
    ({"preview_distances": (float("nan"),)}, "preview_distances"),
    ({"reward_weights": {"heave": True}}, "reward_weights"),
    ({"reward_weights": {"heaving": 1.0}}, "reward weight"), ({"reward_fn": 3}, "reward_fn"),
    ({"observation_fn": 3}, "observation_fn"), ({"sea_generator": "random"}, "sea_generator"),
    ({"slack_tension": float("nan")}, "slack_tension"), ({"over_tension_fraction": "a"}, "over_tension_fraction"),
    ({"over_tension_fraction": 1.0}, "over_tension_fraction"), ({"body": 3}, "body"), ({"body": "ship"}, "body"),
    ({"sim_overrides": {"nope": 1}}, "sim_overrides"), ({"sim_overrides": [1]}, "sim_overrides"),
    ({"scene_overrides": {"nope": 1}}, "scene_overrides"), ({"scene": "nope"}, "scene"), ({"scene": 3}, "scene"),
    ({"fidelity": 2.0}, "fidelity"), ({"render_mode": "ascii"}, "render_mode"), ({"mru_delay": True}, "mru_delay"),
    ({"mean_time_constant": 0.0}, "mean_time_constant"), ({"termination": 3}, "termination"),
    ({"termination": _BadLimits()}, "termination"), ({"renderer": "side"}, "renderer"),
]
BAD_WINCH = [({"winch_class": ["standard"]}, "winch_class"), ({"winch_class": "huge"}, "winch_class"),
             ({"winch_max_speed": 0.0}, "winch_max_speed"),
             ({"winch_max_acceleration": "fast"}, "winch_max_acceleration"),
             ({"winch_travel": 1e6}, "winch_travel")]
BAD_COMP = [({"compensator_class": 4}, "compensator_class"), ({"stiffness_floor": "a"}, "stiffness_floor"),
            ({"damping_floor": float("nan")}, "damping_floor"), ({"stiffness_floor": 1e9}, "stiffness_floor")]


@pytest.mark.parametrize("cls, kw, name", [(c, kw, n) for c in CLASSES for kw, n in BAD_KWARGS]
                         + [(WinchPayoutEnv, kw, n) for kw, n in BAD_WINCH]
                         + [(CompensatorGainsEnv, kw, n) for kw, n in BAD_COMP])
def test_bad_constructor_keywords_raise_config_error_naming_the_keyword(cls, kw, name):
    with pytest.raises(ConfigError) as exc:
        cls(**kw)
    assert name in str(exc.value) and isinstance(exc.value, ValueError)
    assert str(exc.value).startswith(cls.__name__)


def test_unknown_keyword_is_a_type_error():
    with pytest.raises(TypeError, match="nope"):
        WinchPayoutEnv(nope=1)


def test_vector_env_keywords_validated():
    for kw, name in (({"num_envs": 0}, "num_envs"), ({"num_envs": "2"}, "num_envs"), ({"num_envs": 1.5}, "num_envs"),
                     ({"num_envs": 2, "autoreset_mode": "sometimes"}, "autoreset_mode"),
                     ({"num_envs": 2, "parallel": "yes"}, "parallel"),
                     ({"num_envs": 2, "breaking_load": 0.0}, "breaking_load")):
        with pytest.raises(ConfigError, match=name):
            WinchPayoutVectorEnv(**kw)


BAD_OPTIONS = [
    ({"sea_state": "calm"}, "sea_state"), ({"sea_state": None}, "sea_state"), ({"seastate": 4}, "seastate"),
    ({"eval_index": 12}, "eval_index"), ({"eval_index": -1}, "eval_index"), ({"eval_index": 1.0}, "eval_index"),
    ({"eval_index": True}, "eval_index"), ({"eval_index": 0, "sea_state": SeaState(1.0, 5.0)}, "eval_index"),
    ({"sea_seed": 3}, "sea_seed"), ({"sea_state": SeaState(1.0, 5.0), "sea_seed": -1}, "sea_seed"),
    ({"sea_state": SeaState(1.0, 5.0), "sea_seed": "7"}, "sea_seed"), ({"vessel_speed": 0.0}, "vessel_speed"),
    ({"vessel_speed": 100.0}, "vessel_speed"), ({"vessel_speed": float("nan")}, "vessel_speed"),
    ({"cable_length": 5.0}, "cable_length"), ({"cable_length": "long"}, "cable_length"),
]


@pytest.mark.parametrize("cls", CLASSES)
@pytest.mark.parametrize("options, name", BAD_OPTIONS)
def test_bad_reset_options_raise_config_error_naming_the_option(cls, options, name):
    env = _env(cls)
    with pytest.raises(ConfigError) as exc:
        env.reset(seed=0, options=options)
    assert name in str(exc.value)
    with pytest.raises(ConfigError, match="options"):
        env.reset(options="calm")


def test_reset_seed_checked():
    env = _env(WinchPayoutEnv)
    for bad in (-1, 1.5, "0", True):
        with pytest.raises(ConfigError, match="seed"):
            env.reset(seed=bad)
    a = env.reset(seed=np.int64(7))[0]
    np.testing.assert_array_equal(a, env.reset(seed=7)[0])


def test_valid_reset_options_still_work():
    env = WinchPayoutEnv(episode_seconds=1.0)
    sea = SeaState.from_code(4, "coastal")
    _, info = env.reset(seed=0, options={"sea_state": sea, "sea_seed": np.int64(5), "vessel_speed": 2.5})
    assert info["sea_seed"] == 5 and info["vessel_speed"] == 2.5
    _, info = env.reset(seed=0, options={"eval_index": np.int32(11), "cable_length": 90, "vessel_speed": None})
    assert info["cable_length"] == 90.0
    _finite_step(env.step(np.zeros(1)))


# ======================================================================================== fuzz
def _bad_numbers():
    return st.sampled_from([float("nan"), float("inf"), -float("inf"), -1.0, 0.0, True, "1", None, [1.0],
                            1e300, -1e300])


def _num(lo, hi):
    return st.floats(lo, hi, allow_nan=False)


# keyword -> (valid values, invalid or extreme values)
KWARGS = {
    "control_hz": (st.sampled_from([5.0, 10.0, 20.0]), _bad_numbers()),
    "dt": (st.sampled_from([None, 0.025, 0.05, 0.1]), _bad_numbers()),
    "episode_seconds": (_num(0.05, 2.0), _bad_numbers()),
    "sea_codes": (st.lists(st.integers(0, 9), min_size=1, max_size=3),
                  st.one_of(st.just(()), st.just("34"), st.lists(st.integers(10, 99), min_size=1, max_size=2),
                            st.just((3.5,)), st.just((True,)))),
    "sea_convention": (st.sampled_from(["coastal", "open_ocean"]), st.sampled_from(["calm", "", None, 3])),
    "heading_deg": (_num(-720, 720), st.sampled_from([float("nan"), "head", None])),
    "heading_spread_deg": (_num(0, 180), st.sampled_from([-1.0, 181.0, float("nan"), None])),
    "vessel_speeds": (st.lists(_num(0.5, 5.0), min_size=1, max_size=2),
                      st.one_of(st.just(()), st.just("3"), st.lists(_num(-5.0, 0.0), min_size=1, max_size=2),
                                st.just((1e9,)), st.just((float("nan"),)))),
    "cable_lengths": (st.lists(_num(40.0, 150.0), min_size=1, max_size=2),
                      st.one_of(st.just(()), st.lists(_num(-5.0, 15.0), min_size=1, max_size=2),
                                st.just((float("inf"),)))),
    "observations": (st.lists(st.sampled_from(["fish_heave", "fish_pitch", "top_tension", "time_left", "last_action"]),
                              min_size=1, max_size=3, unique=True),
                     st.one_of(st.just("fish_heave"), st.just(("nope",)), st.just((1,)), st.just(("fish_heave",) * 2))),
    "sensor_noise": (st.fixed_dictionaries({"fish_heave_dev": _num(0.0, 10.0)}),
                     st.one_of(st.just({"fish_heave_dev": -1.0}), st.just({"nope": 0.1}), st.just([0.1]),
                               st.just({"fish_heave_dev": float("nan")}))),
    "obs_delay": (st.integers(0, 3), st.one_of(st.just(-1), st.just(1.5), st.just(float("nan")), st.just(10 ** 6))),
    "preview_distances": (st.lists(_num(-100.0, 100.0), max_size=2), st.sampled_from([(float("nan"),), "10", (None,)])),
    "reward_weights": (st.fixed_dictionaries({"heave": _num(0.0, 1e6)}),
                       st.sampled_from([{"heave": -1.0}, {"heaving": 1.0}, {"heave": float("nan")}, "heave"])),
    "slack_tension": (_num(0.0, 1e4), _bad_numbers()),
    "over_tension_fraction": (_num(0.0, 0.99), st.sampled_from([1.0, -0.1, float("nan"), "half"])),
    "breaking_load": (st.one_of(st.none(), _num(1e3, 1e6), st.just({"primary": 2e5, "secondary": None})),
                      st.one_of(_bad_numbers(), st.just({"primary": 0.0}), st.just({"tether": 1e5}))),
    "floor_depth": (st.one_of(st.none(), _num(10.0, 500.0)), _bad_numbers().filter(lambda v: v is not None)),
    "body": (st.sampled_from(["fish", "depressor"]), st.sampled_from(["ship", 3, None])),
    "sim_overrides": (st.sampled_from([None, {"max_step_cuts": 0}]), st.sampled_from([{"nope": 1}, [1], "x"])),
    "mru_delay": (_num(0.0, 0.5), st.sampled_from([-0.1, 6.0, float("nan"), True])),
    "mean_time_constant": (st.one_of(st.none(), _num(0.1, 100.0)), st.sampled_from([0.0, -1.0, float("inf"), "x"])),
    "fidelity": (st.none(), st.sampled_from([0.0, 1.0, float("nan"), "high"])),
    "render_mode": (st.sampled_from([None, "rgb_array"]), st.sampled_from(["ascii", 1])),
    "termination": (st.sampled_from([None, Limits(), PartedOrGrounded(50.0)]), st.sampled_from([3, "floor", _BadLimits()])),
    "renderer": (st.none(), st.sampled_from(["side", 3])),
}
WINCH_KWARGS = {
    "winch_class": (st.sampled_from(["standard", "high_performance"]), st.sampled_from(["huge", None, 1])),
    "winch_max_speed": (st.one_of(st.none(), _num(0.1, 5.0)), _bad_numbers().filter(lambda v: v is not None)),
    "winch_travel": (st.one_of(st.none(), _num(1.0, 20.0)), st.sampled_from([0.0, 1e6, float("nan")])),
}
COMP_KWARGS = {
    "compensator_class": (st.sampled_from([None, "sheave_2m", "deep_tow_4m"]), st.sampled_from(["huge", 1])),
    "stiffness_floor": (st.one_of(st.none(), _num(1.0, 1e5)), st.sampled_from([0.0, 1e9, float("nan"), "a"])),
}


@st.composite
def _configs(draw):
    cls = draw(st.sampled_from(CLASSES))
    table = dict(KWARGS, **(WINCH_KWARGS if cls is WinchPayoutEnv else COMP_KWARGS))
    names = draw(st.lists(st.sampled_from(sorted(table)), min_size=1, max_size=3, unique=True))
    kw = {}
    for n in names:
        good, bad = table[n]
        kw[n] = draw(st.one_of(good, bad))
    return cls, kw


def _action_strategy(dim):
    # right and wrong shapes, real and unreal dtypes, odd values
    shapes = st.sampled_from([(dim,), (), (1,), (2,), (3,), (dim, 1), (1, dim), (0,)])
    dtypes = st.sampled_from([np.float32, np.float64, np.float16, np.int64, np.uint8, bool, complex, object, str])
    values = st.floats(allow_nan=True, allow_infinity=True, width=32)

    @st.composite
    def arrays(draw):
        shape, dtype = draw(shapes), draw(dtypes)
        n = int(np.prod(shape)) if shape else 1
        vals = draw(st.lists(values, min_size=n, max_size=n))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return np.array(vals, dtype=float).astype(dtype).reshape(shape)
    others = st.one_of(st.none(), st.text(max_size=3), st.floats(allow_nan=True), st.integers(-5, 5), st.booleans(),
                       st.lists(st.floats(-2, 2), min_size=0, max_size=3), st.lists(st.text(max_size=2), max_size=2),
                       st.complex_numbers(max_magnitude=2))
    return st.one_of(arrays(), others)


def _action_ok(a, dim) -> bool:
    """The documented rule: real numbers (float or integer dtype), shape (dim,) — or a scalar when dim == 1."""
    try:
        arr = np.asarray(a)
    except Exception:
        return False
    return arr.dtype.kind in "fiu" and (arr.shape == (dim,) or (dim == 1 and arr.shape == ()))


def _assert_step_or_action_error(env, a, dim):
    ok = _action_ok(a, dim)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = env.step(a)
    except ActionError as exc:
        assert not ok, (a, exc)
        assert "action space" in str(exc) and "shape" in str(exc)
        return False
    assert ok, a
    return _finite_step(out)


@settings(FUZZ, max_examples=400)
@given(_configs(), st.data())
def test_fuzz_constructor_keywords(config, data):
    """Any mix of (valid, invalid, extreme) keywords: ConfigError naming one of the keywords given, or an env
    whose reset and first steps are finite."""
    cls, kw = config
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")                  # e.g. a control period that is not a whole number of dt
            env = cls(**kw)
    except ConfigError as exc:
        event("ConfigError")
        assert isinstance(exc, ValueError)
        assert any(k in str(exc) for k in kw) or ("observation" in str(exc) and "observations" in kw), (kw, exc)
        return
    event("constructed")
    obs, info = env.reset(seed=data.draw(st.integers(0, 2 ** 31 - 1)))
    assert np.all(np.isfinite(obs)) and env.observation_space.contains(obs)
    for _ in range(3):
        if _finite_step(env.step(env.action_space.sample())):
            break


def _options_strategy():
    sea = st.builds(SeaState.from_code, st.integers(0, 7), st.sampled_from(["coastal", "open_ocean"]))
    good = {
        "eval_index": st.integers(0, 11), "sea_state": sea, "sea_seed": st.integers(0, 2 ** 40),
        "vessel_speed": st.sampled_from([None, 2.0, 3.0]), "cable_length": st.sampled_from([None, 80.0, 95.0]),
    }
    bad = {
        "eval_index": st.one_of(st.integers(12, 100), st.integers(-100, -1), st.just(1.0), st.just("0"), st.just(True)),
        "sea_state": st.sampled_from(["calm", 4, None, {"hs": 1.0}]),
        "sea_seed": st.one_of(st.integers(-100, -1), st.just(1.5), st.just("7"), st.just(None)),
        "vessel_speed": _bad_numbers().filter(lambda v: v is not None),
        "cable_length": st.one_of(_bad_numbers().filter(lambda v: v is not None), _num(0.1, 19.0)),
        "unknown": st.just(1),
    }

    @st.composite
    def opts(draw):
        # a coherent set of options (sea from the eval set, a given sea (and seed) or drawn; a configuration) ...
        mode = draw(st.sampled_from(["eval", "sea", "sea+seed", "drawn"]))
        out = {"eval": {"eval_index": None}, "sea": {"sea_state": None},
               "sea+seed": {"sea_state": None, "sea_seed": None}, "drawn": {}}[mode]
        for k in ("vessel_speed", "cable_length"):
            if draw(st.booleans()):
                out[k] = None
        out = {k: draw(good[k]) for k in out}
        # ... then, in most examples, one to two keys made bad (or unknown, or conflicting)
        for k in draw(st.lists(st.sampled_from(sorted(bad)), max_size=2, unique=True)):
            out["sea_stat" if k == "unknown" else k] = draw(bad[k])
        return out
    return st.one_of(st.none(), opts(), st.sampled_from(["calm", 3, [("eval_index", 0)]]))


@settings(FUZZ, max_examples=400)
@given(st.sampled_from(CLASSES), _options_strategy())
def test_fuzz_reset_options(cls, options):
    """Any reset options: ConfigError naming an option, or a finite first observation and step."""
    env = _env(cls)
    try:
        obs, info = env.reset(seed=0, options=options)
    except ConfigError as exc:
        event("ConfigError")
        names = list(options) if isinstance(options, dict) else ["options"]
        assert any(k in str(exc) for k in names), (options, exc)
        return
    event("reset")
    assert np.all(np.isfinite(obs)) and env.observation_space.contains(obs)
    _finite_step(env.step(env.action_space.sample()))


@settings(FUZZ, max_examples=400)
@given(st.sampled_from(CLASSES), st.data())
def test_fuzz_actions_single_env(cls, data):
    """Any action: ActionError naming the action space (exactly when the documented rule refuses it), or a
    finite step; stepping on after the episode ended raises ResetNeeded."""
    env = _env(cls)                                      # episode_seconds = 1: 10 steps
    dim = env.action_space.shape[0]
    seed = data.draw(st.integers(0, 100))
    steps = data.draw(st.integers(0, 12))
    actions = data.draw(st.lists(_action_strategy(dim), min_size=1, max_size=4))
    env.reset(seed=seed)
    done = False
    for _ in range(steps):                               # advance with valid actions (maybe to the end)
        if _finite_step(env.step(env.action_space.sample())):
            done = True
            break
    for a in actions:
        if done:
            with pytest.raises(ResetNeeded, match="ended"):
                env.step(a)
            continue
        done = _assert_step_or_action_error(env, a, dim) is True


_VENVS: dict = {}


@settings(FUZZ, max_examples=300)
@given(st.sampled_from(CLASSES), st.data())
def test_fuzz_actions_vector_env(cls, data):
    """The batched env: actions of shape (num_envs, act_dim) (or (num_envs,) for a one-dimensional action) of
    real numbers are stepped (finite results; finished copies auto-reset), anything else is an ActionError."""
    if cls not in _VENVS:
        _VENVS[cls] = VECTOR[cls](2, episode_seconds=0.5)
        _VENVS[cls].reset(seed=0)
    venv = _VENVS[cls]
    dim = venv.single_action_space.shape[0]
    shape = st.sampled_from([(2, dim), (2,), (dim,), (1, dim), (2, dim, 1), (3, dim), (2, 3)])
    dtype = st.sampled_from([np.float32, np.float64, np.int32, bool, complex, object])
    s, dt = data.draw(shape), data.draw(dtype)
    vals = data.draw(st.lists(st.floats(allow_nan=True, width=32), min_size=int(np.prod(s)), max_size=int(np.prod(s))))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = np.array(vals, dtype=float).astype(dt).reshape(s)
    ok = a.dtype.kind in "fiu" and (s == (2, dim) or (dim == 1 and s == (2,)))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            obs, rew, te, tr, _ = venv.step(a)
    except ActionError as exc:
        assert not ok and "action space" in str(exc)
        return
    assert ok and np.all(np.isfinite(obs)) and np.all(np.isfinite(rew))
