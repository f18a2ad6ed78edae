"""What defines a `utamp train` run and what it yields: `TrainConfig`, `TrainResult`, the
algorithms' default settings (`default_hyperparams`) and the slot policy's training width and
head (`slot_policy_kwargs`). Light: no torch or stable-baselines3 here, so the CLI's parser and
the results scripts read these without loading a model.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from utamp_gym.env.object_goal import GOAL_KEYS
from utamp_gym.env.options import INTERFACES, MASKS
from utamp_gym.rl.envs import DEFAULT_OBS_KEYS, OBJECT_OBS_KEYS, default_interface, env_option
from utamp_gym.rl.policy import ALGOS

#: the slot policy's width in `utamp train` (`utamp_gym.rl.slots.D_MODEL`, 64, is the width of
#: a model saved without ``features_extractor_kwargs``): 32 trains several times faster per env
#: step (benchmarks/train_speed.py) and learns as much per env step
#: (benchmarks/train_speed_learning.py)
SLOT_TRAIN_D_MODEL = 32
#: the slot policy's action head in `utamp train` (`utamp_gym.rl.slots.HEADS`; "pairs" for a
#: model saved without one)
SLOT_TRAIN_HEAD = "pointer"


def slot_policy_kwargs() -> dict[str, Any]:
    """The slot policy's ``policy_kwargs`` for `utamp train` (saved with the model, so it
    loads with the width and head it was trained with)."""
    return {"features_extractor_kwargs": {"d_model": SLOT_TRAIN_D_MODEL}, "head": SLOT_TRAIN_HEAD}


GROUNDINGS = ("symbolic", "physics")
#: env options `TrainConfig` sets through fields of its own, not `TrainConfig.env_options`
_SET_BY_CONFIG = frozenset({"grounding", "num_objects", "masks", "interface", "reward_shaping",
                            "terminate_on_failure"})  # fmt: skip
#: PPO epochs per rollout of the slot policy: the update is most of its training time, and 3
#: epochs learn within the interval of 10 per env step (benchmarks/train_speed_learning.py)
OBJECTS_EPOCHS = 3
#: what `train` trains: the RL algorithms, and behaviour cloning from demonstrations
TRAIN_ALGOS = (*ALGOS, "bc")


@dataclass(frozen=True)
class TrainConfig:
    """Everything that defines a run (written to ``train.json``).

    `num_objects` None trains on every scene of the suite (2–5 objects); `hyperparams`
    overrides `default_hyperparams`; `obs_keys` are the observation entries the agent sees;
    `interface` is the env option (``objects``: MaskablePPO with `utamp_gym.rl.slots.SlotPolicy`
    over all of the objects interface's entries; ``""``: the env's own, `default_interface`);
    `init_from` is a model zip whose policy weights the run starts from (fine-tuning a
    behaviour-cloned policy); `stop_at_plateau` (a success gain, e.g. 0.02) stops training at
    the first evaluation where the last 20 % of the curve gained less
    (`utamp_gym.rl.callbacks.plateaued`); `time_limit_s` stops it at the first evaluation after
    that much training time (a budget on a shared machine; the steps reached are recorded);
    `env_options` are more ``gym.make`` options of the training and evaluation envs, saved
    with the model (e.g. ``{"slots": 8}``: an objects interface for procedural-v2's 8-object
    scenes). On an env with the goal in its observation (``goal_observation``, e.g.
    ``UTampKitchenGoals-v0``) the objects interface's entries include the goal's.
    """

    env_id: str = "UTampKitchen-v0"
    algo: str = "maskable-ppo"
    grounding: str = "symbolic"
    num_objects: int | None = None
    masks: str = "affordances"
    steps: int = 200_000
    n_envs: int = 8
    seed: int = 0
    eval_every: int = 10_000
    eval_episodes: int = 60
    eval_masks: bool = True
    target_success: float = 0.9
    stop_at_target: bool = False
    stop_at_plateau: float | None = None
    time_limit_s: float | None = None
    reward_shaping: bool = True
    terminate_on_failure: bool = False
    obs_keys: tuple[str, ...] = DEFAULT_OBS_KEYS
    hyperparams: dict[str, Any] = field(default_factory=dict)
    interface: str = ""
    init_from: str = ""
    demos: str = ""
    env_options: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.interface:
            object.__setattr__(self, "interface", default_interface(self.env_id, self.algo))

        if self.interface not in INTERFACES:
            raise ValueError(f"unknown interface {self.interface!r}; valid: grounded, objects")
        if self.interface == "objects":
            if self.algo not in ("maskable-ppo", "bc"):
                raise ValueError(
                    f"interface 'objects' trains maskable-ppo with the slot policy "
                    f"(utamp_gym.rl.slots), not {self.algo!r}"
                )
            if tuple(self.obs_keys) == DEFAULT_OBS_KEYS:  # the objects interface's entries
                goal = env_option(self.env_id, "goal_observation", self.env_options)
                object.__setattr__(self, "obs_keys", OBJECT_OBS_KEYS + (GOAL_KEYS if goal else ()))
        if not isinstance(self.env_options, dict) or set(self.env_options) & _SET_BY_CONFIG:
            raise ValueError(
                f"env_options must be a dict of gym.make options other than "
                f"{', '.join(sorted(_SET_BY_CONFIG))} (fields of their own), "
                f"got {self.env_options!r}"
            )
        if self.algo not in TRAIN_ALGOS:
            raise ValueError(f"unknown algo {self.algo!r}; valid: {', '.join(TRAIN_ALGOS)}")
        if (self.algo == "bc") != bool(self.demos):
            raise ValueError("algo 'bc' (and only it) needs demos: a `utamp demos` dataset folder")
        if self.algo == "bc" and self.interface != "objects":
            raise ValueError("behaviour cloning trains the slot policy: use interface 'objects'")
        if self.grounding not in GROUNDINGS:
            raise ValueError(f"unknown grounding {self.grounding!r}; valid: symbolic, physics")
        if self.masks not in MASKS:
            raise ValueError(f"unknown masks {self.masks!r}; valid: {', '.join(MASKS)}")
        for name in ("steps", "n_envs", "eval_every", "eval_episodes"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be a positive integer, got {getattr(self, name)}")


@dataclass(frozen=True)
class TrainResult:
    """What `train` produced: paths, steps, times and the evaluation curve.

    `wall_time_s` is the whole call; `train_time_s` leaves out the evaluations and
    checkpoints, as do the curve's times and `time_to_target_s` (training time until the
    first evaluation with success ≥ `TrainConfig.target_success`).
    """

    out: Path
    model_path: Path
    steps: int
    wall_time_s: float
    train_time_s: float
    final_success: float
    steps_to_target: int | None
    time_to_target_s: float | None
    curve: list[dict[str, Any]]


def default_hyperparams(algo: str, n_envs: int, interface: str = "grounded") -> dict[str, Any]:
    """The algorithm settings used unless `TrainConfig.hyperparams` overrides them (the slot
    policy of the objects interface at `slot_policy_kwargs`)."""
    objects = interface == "objects"
    net: dict[str, Any] = slot_policy_kwargs() if objects else {"net_arch": [128, 128]}
    if algo == "dqn":
        return {
            "learning_rate": 1e-4, "buffer_size": 100_000, "learning_starts": 1_000,
            "batch_size": 64, "gamma": 0.99, "train_freq": 4, "target_update_interval": 1_000,
            "exploration_fraction": 0.3, "exploration_final_eps": 0.05, "policy_kwargs": net,
        }  # fmt: skip
    return {
        "learning_rate": 3e-4, "n_steps": max(16, 1024 // n_envs), "batch_size": 256,
        "n_epochs": OBJECTS_EPOCHS if objects else 10, "gamma": 0.99, "gae_lambda": 0.95,
        "ent_coef": 0.01, "policy_kwargs": net,
    }  # fmt: skip
