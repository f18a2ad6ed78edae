"""Object slots and env options of saved agents: `utamp train` / `utamp demos` set ``slots``,
``domain`` and ``affordances`` on the command line; an objects-interface model acts with its
own slot count (a suite of larger scenes is refused up front, naming the fix); ``rl:PATH``
episodes of one process share their symbolic env without changing a row."""

from __future__ import annotations

import argparse
import json
import shlex
import zipfile
from pathlib import Path

import gymnasium as gym
import pytest

pytest.importorskip("sb3_contrib")

from utamp_gym.cli import main
from utamp_gym.data.minari_io import episode_metadata, load_dataset
from utamp_gym.env.object_goal import GOAL_KEYS
from utamp_gym.env.object_space import MAX_SLOTS, n_actions, slots_for_actions
from utamp_gym.rl import harness
from utamp_gym.rl.cli import add_train_parser, env_option_flags, train_config
from utamp_gym.rl.envs import DEFAULT_OBS_KEYS, OBJECT_OBS_KEYS
from utamp_gym.rl.saved import META_NAME, ModelError, ModelMeta, read_meta
from utamp_gym.rl.train import train

GOALS = "UTampKitchenGoals-v0"
V2_OPTIONS = {"domain": "utamp2x", "affordances": "rules"}


def test_slot_count_is_read_back_from_an_action_space_size() -> None:
    assert [slots_for_actions(n_actions(k)) for k in range(1, MAX_SLOTS + 1)] == list(
        range(1, MAX_SLOTS + 1)
    )
    assert slots_for_actions(n_actions(6) + 1) is None


def _meta_zip(path: Path, **options: object) -> Path:
    """A zip holding only a model's metadata (what the up-front checks read)."""
    options = {"masks": "affordances", "interface": "objects", **options}
    meta = ModelMeta(env_id=GOALS, suite="procedural-v2/train", algo="maskable-ppo",
                     obs_keys=("present",), n_actions=n_actions(6), n_fluents=0,
                     env_options=options)  # fmt: skip
    with zipfile.ZipFile(path, "w") as z:
        z.writestr(META_NAME, json.dumps(meta.to_json()))
    return path


def test_a_model_acts_with_its_own_slot_count(tmp_path: Path) -> None:
    old = read_meta(_meta_zip(tmp_path / "old.zip", **V2_OPTIONS))  # saved without "slots"
    assert harness.model_slots(old) == 6
    assert harness.model_env_options(old)["slots"] == 6
    new = read_meta(_meta_zip(tmp_path / "new.zip", slots=8, **V2_OPTIONS))
    assert harness.model_slots(new) == 8
    grounded = ModelMeta(env_id="UTampKitchen-v0", suite="pick-place", algo="maskable-ppo",
                         obs_keys=("symbolic",), n_actions=10, n_fluents=3)  # fmt: skip
    assert harness.model_slots(grounded) is None and "slots" not in harness.model_env_options(
        grounded
    )


def test_a_suite_of_larger_scenes_is_refused_up_front(tmp_path: Path, capsys) -> None:
    model = _meta_zip(tmp_path / "six.zip", **V2_OPTIONS)
    with pytest.raises(ModelError, match=r"acts on 6 object slots, but scene 'procedural-v2/"
                       r"test-count/\d+' of procedural-v2/test-count has 8 objects: .*"
                       r"train with --slots 8"):  # fmt: skip
        harness.check_rl_method(f"rl:{model}", "procedural-v2/test-count", spaces=False)
    harness.check_rl_method(f"rl:{model}", "procedural-v2/test-tasks", spaces=False)
    out = tmp_path / "eval"
    assert main(["eval", "--suite", "procedural-v2/test-count", "--methods", f"rl:{model}",
                 "--grounding", "symbolic", "--out", str(out)]) == 2  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "acts on 6 object slots" in err[0] and not out.exists()


def _train_args(line: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_train_parser(parser.add_subparsers())
    return parser.parse_args(shlex.split(f"train {line} --out x"))


def test_train_flags_set_the_env_options() -> None:
    args = _train_args("--interface objects --slots 8 --domain utamp2x --affordances rules")
    assert env_option_flags(args, "objects") == {"slots": 8, **V2_OPTIONS}
    assert env_option_flags(_train_args(""), "grounded") == {}


@pytest.mark.parametrize(
    ("line", "interface", "keys"),
    [
        ("--env UTampKitchen-v0", "grounded", DEFAULT_OBS_KEYS),
        ("--env UTampKitchen-v0 --interface objects", "objects", OBJECT_OBS_KEYS),
        ("--env UTampKitchenProcedural-v0", "objects", OBJECT_OBS_KEYS),
        (f"--env {GOALS} --interface objects --slots 8 --domain utamp2x --affordances rules",
         "objects", OBJECT_OBS_KEYS + GOAL_KEYS),
        ("--env UTampKitchenProcedural-v0 --algo ppo", "grounded", DEFAULT_OBS_KEYS),
    ],
)  # fmt: skip
def test_a_train_parse_gives_one_config_with_its_interfaces_obs_keys(
    line: str, interface: str, keys: tuple[str, ...]
) -> None:
    config, kwargs = train_config(_train_args(line))
    assert (config.interface, config.obs_keys) == (interface, keys)
    assert config.env_options == kwargs.get("env_options", {})


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("train --slots 0 --out {out}", "argument --slots: must be an integer in 1..16, got 0"),
        ("train --domain utamp3 --out {out}", "argument --domain: invalid choice: 'utamp3'"),
        ("train --env UTampKitchen-v0 --slots 8 --out {out}",
         "--slots sets the objects interface's slots, not the grounded one's: add --interface "
         "objects"),
        (f"train --env {GOALS} --domain utamp2x --masks geometric --out {{out}}",
         "--masks geometric needs --domain utamp2"),
        ("demos --suite procedural-v2/train --domain utamp2x --out {out}",
         "--masks geometric needs --domain utamp2"),
        ("demos --suite pick-place --track low-level --slots 8 --out {out}",
         "--slots, --domain and --affordances are options of the macro track's env"),
    ],
)  # fmt: skip
def test_bad_env_option_flags_are_one_line_errors_before_any_work(
    tmp_path: Path, capsys, line: str, message: str
) -> None:
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exit_info:
        code = main(shlex.split(line.format(out=out)))
        raise SystemExit(code)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not out.exists()


def test_demos_record_in_the_env_the_flags_name(tmp_path: Path, capsys) -> None:
    pytest.importorskip("minari")
    args = ("demos --suite procedural-v2/train --episodes 2 --method utamp2x-rules --masks "
            "affordances --slots 8 --domain utamp2x --affordances rules --out "
            f"{tmp_path}")  # fmt: skip
    assert main(shlex.split(args)) == 0
    out, err = capsys.readouterr()
    assert "2 episodes" in out and err == ""
    data = load_dataset(tmp_path, "utamp/procedural-v2-train-macro-utamp2x-rules-v0")
    options = episode_metadata(data, 0)["env_options"]
    assert {k: options[k] for k in ("slots", "domain", "affordances")} == {"slots": 8, **V2_OPTIONS}


@pytest.fixture(scope="module")
def tiny_goals_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("goals")
    train(GOALS, steps=32, n_envs=1, out=out, eval_every=32, eval_episodes=1, progress=False,
          interface="objects", hyperparams={"n_steps": 32, "batch_size": 32},
          env_options={"slots": 8, **V2_OPTIONS})  # fmt: skip
    return out / "model.zip"


def test_saved_objects_models_record_their_slots(tiny_goals_model: Path) -> None:
    assert read_meta(tiny_goals_model).env_options["slots"] == 8


def test_episodes_sharing_an_env_match_episodes_in_a_new_one(tiny_goals_model: Path) -> None:
    method = f"rl:{tiny_goals_model}"
    first, second = "procedural-v2/test-count/0000", "procedural-v2/test-count/0001"
    fresh = harness.run_rl_episode(method, first, 0, "symbolic")  # its own env, closed
    with harness.EnvCache() as envs:
        shared = harness.run_rl_episode(method, first, 0, "symbolic", envs=envs)
        env = envs.get(*_env_of(tiny_goals_model))
        harness.run_rl_episode(method, second, 1, "symbolic", envs=envs)
        again = harness.run_rl_episode(method, first, 0, "symbolic", envs=envs)
        assert envs.get(*_env_of(tiny_goals_model)) is env  # one env served all three episodes
    for ep in (shared, again):
        assert (ep.success, ep.actions, ep.reason) == (fresh.success, fresh.actions, fresh.reason)
    assert fresh.actions  # it acted


def _env_of(model: Path) -> tuple[str, str, dict[str, object]]:
    """The (env id, grounding, options) `run_rl_episode` makes a symbolic episode's env with
    for the procedural-v2 test-count scenes."""
    meta = read_meta(model)
    options = {**harness.model_env_options(meta), "disturbance": 0.0,
               **harness.suite_options("procedural-v2/test-count/0000"),
               "reward_shaping": False, "terminate_on_failure": False,
               "record_timings": False}  # fmt: skip
    return meta.env_id, "symbolic", options


class _Closable(gym.Env):
    """A real gymnasium env that says whether it was closed."""

    observation_space = gym.spaces.Discrete(1)
    action_space = gym.spaces.Discrete(1)

    def __init__(self, grounding: str, size: int) -> None:
        self.grounding, self.size, self.closed = grounding, size, False

    def close(self) -> None:
        self.closed = True


def test_an_env_cache_reuses_its_env_for_equal_options_and_closes_it_on_new_ones() -> None:
    if "TestClosable-v0" not in gym.registry:
        gym.register("TestClosable-v0", entry_point=_Closable)
    with harness.EnvCache() as envs:
        first = envs.get("TestClosable-v0", "symbolic", {"size": 1})
        assert envs.get("TestClosable-v0", "symbolic", {"size": 1}) is first
        assert not first.unwrapped.closed
        second = envs.get("TestClosable-v0", "symbolic", {"size": 2})
        assert second.unwrapped.size == 2 and first.unwrapped.closed
        assert not second.unwrapped.closed
    assert second.unwrapped.closed  # the owner's close closed the last one
