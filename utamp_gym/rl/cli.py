"""`utamp train`: the RL baselines on the command line (wired into `utamp_gym.cli`).

    utamp train --env UTampKitchen-v0 --algo maskable-ppo|ppo|dqn [--grounding symbolic|physics]
        [--masks affordances|geometric|none] [--interface grounded|objects] [--init-from ZIP]
        [--num-objects N] [--slots N] [--domain D] [--affordances A] [--steps N] [--envs K]
        [--seed S] [--seeds K [--executor local|ray] [--workers N] [--ray-address A]]
        --out DIR

With ``--seeds K`` (K > 1) the seeds S .. S+K-1 train independently into ``DIR/seed_<s>/``
and ``DIR`` gets ``aggregate.json`` and ``learning_curves.png`` (mean and band across seeds);
``--executor ray`` trains them as parallel Ray tasks, ``--executor local --workers N`` in N
local processes.
Heavy imports (torch, stable-baselines3) happen only when the command runs.
"""

from __future__ import annotations

import argparse
from typing import Any

from utamp_gym.affordances.sources import AFFORDANCE_SOURCES
from utamp_gym.distributed import make_executor
from utamp_gym.env.object_space import MAX_SLOTS
from utamp_gym.env.registry import env_ids
from utamp_gym.errors import UtampError
from utamp_gym.extras import require
from utamp_gym.outputs import output_dir
from utamp_gym.rl.config import GROUNDINGS, TRAIN_ALGOS, TrainConfig
from utamp_gym.rl.envs import default_interface
from utamp_gym.symbolic.problem import DOMAINS

#: the env option ``masks`` (`utamp_gym.env.options.MASKS`; repeated here so that building
#: the parser imports no env code; a test keeps the two equal)
MASK_CHOICES = ("affordances", "geometric", "none")


def _positive(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {value}")
    return value


def slots_count(text: str) -> int:
    """``--slots``: object slots of the objects interface, 1..`MAX_SLOTS`."""
    value = int(text)
    if not 1 <= value <= MAX_SLOTS:
        raise argparse.ArgumentTypeError(f"must be an integer in 1..{MAX_SLOTS}, got {value}")
    return value


def add_env_option_flags(p: argparse.ArgumentParser) -> None:
    """``--slots``, ``--domain`` and ``--affordances``: env options of `utamp train` and
    `utamp demos` (saved with a model, so `utamp eval` rebuilds its env)."""
    p.add_argument("--slots", type=slots_count, default=None, metavar="N",
                   help="objects interface: N object slots (default: 6, or the most objects "
                   "of a scene; 8 for procedural-v2/test-count)")  # fmt: skip
    p.add_argument("--domain", choices=DOMAINS, default=None,
                   help="the env's planning domain (default utamp2; utamp2x: the extended one "
                   "procedural-v2's labels assume; needs --masks affordances)")  # fmt: skip
    p.add_argument("--affordances", choices=AFFORDANCE_SOURCES, default=None,
                   help="the affordance source of the masks and the outcome model (default "
                   "gt; rules: derived from the objects' attributes)")  # fmt: skip


def env_option_flags(args: argparse.Namespace, interface: str) -> dict[str, Any]:
    """The env options `add_env_option_flags` set, checked (`UtampError`, one line)."""
    options = {k: getattr(args, k) for k in ("slots", "domain", "affordances")}
    options = {k: v for k, v in options.items() if v is not None}
    if "slots" in options and interface != "objects":
        raise UtampError(f"--slots sets the objects interface's slots, not the {interface} one's: "
                         "add --interface objects")  # fmt: skip
    if options.get("domain", "utamp2") != "utamp2" and args.masks != "affordances":
        raise UtampError(f"--masks {args.masks} needs --domain utamp2 (it drops U-TAMP-2's "
                         f"affordance preconditions); with --domain {options['domain']} use "
                         "--masks affordances")  # fmt: skip
    return options


def train_config(args: argparse.Namespace) -> tuple[TrainConfig, dict[str, Any]]:
    """The run's `TrainConfig`, built once from parsed `utamp train` flags (bad options:
    `UtampError`, one line), and the keyword arguments `train` and `train_seeds` take (its
    fields as given, and ``progress``)."""
    kwargs: dict[str, Any] = {
        "env_id": args.env,
        "algo": args.algo,
        "grounding": args.grounding,
        "num_objects": args.num_objects,
        "steps": args.steps,
        "n_envs": args.envs,
        "eval_every": args.eval_every,
        "eval_episodes": args.eval_episodes,
        "progress": not args.no_progress,
        "stop_at_target": args.stop_at_target,
        "masks": args.masks,
        "interface": args.interface,
        "init_from": args.init_from or "",
        "demos": args.demos or "",
    }
    options = env_option_flags(args, args.interface or default_interface(args.env, args.algo))
    if options:
        kwargs["env_options"] = options
    try:
        config = TrainConfig(seed=args.seed, **{k: v for k, v in kwargs.items() if k != "progress"})
    except ValueError as exc:
        raise UtampError(str(exc)) from None
    return config, kwargs


def _cmd_train(args: argparse.Namespace) -> int:
    require("utamp train", "rl")
    if args.algo == "bc":  # reads a Minari dataset
        require("utamp train --algo bc", "data")
    # the rl extra (torch, stable-baselines3) is checked above, before these load it
    # lazy: utamp_gym.rl.seeds imports sb3_contrib, stable_baselines3, torch
    from utamp_gym.rl.seeds import train_seeds

    # lazy: utamp_gym.rl.train imports sb3_contrib, stable_baselines3, torch
    from utamp_gym.rl.train import train

    config, kwargs = train_config(args)  # every option checked before anything is built
    parallel = args.executor != "local" or args.workers is not None or args.ray_address
    if parallel and args.seeds == 1:
        raise UtampError("--executor, --workers and --ray-address need --seeds K > 1")
    if args.executor == "ray":
        require("utamp train --executor ray", "ray")
    output_dir(args.out, "--out")  # before training, not after
    if args.seeds > 1:
        workers = args.workers
        if args.executor == "local" and workers is None:
            workers = 0  # one seed after another in this process
        executor = make_executor(args.executor, workers=workers, ray_address=args.ray_address)
        agg = train_seeds(args.seeds, out=args.out, seed=args.seed, executor=executor, **kwargs)
        steps = agg["steps_to_target"]["mean"]
        reached = (
            f"{agg['reached']}/{args.seeds} seeds, mean {steps:.0f} steps"
            if steps is not None
            else f"0/{args.seeds} seeds"
        )
        final = agg["final_success"]
        print(
            f"{args.algo} (masks {args.masks}), {args.seeds} seeds: final success "
            f"{final['mean']:.2f} ± {final['std']:.2f}; target success "
            f"{config.target_success:.2f} reached by {reached}; "
            f"wrote aggregate.json and learning_curves.png to {args.out}"
        )
        return 0
    result = train(seed=args.seed, out=args.out, **kwargs)
    reached = (
        f"reached at {result.steps_to_target} steps ({result.time_to_target_s:.1f} s)"
        if result.steps_to_target is not None
        else "not reached"
    )
    print(
        f"{args.algo}: {result.steps} steps in {result.wall_time_s:.1f} s, final success "
        f"{result.final_success:.2f}; target success {config.target_success:.2f} {reached}; "
        f"model: {result.model_path}"
    )
    return 0


def add_train_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``train`` command to `subparsers` (from ``parser.add_subparsers()``)."""
    p = subparsers.add_parser(
        "train",
        help="train a baseline: MaskablePPO, PPO, DQN or behaviour cloning (bc)",
        description="Train an RL agent on a kitchen env; writes model.zip, checkpoints/, "
        "learning_curve.png and train.json to --out (with --seeds K > 1: one folder per "
        "seed plus aggregate.json and learning_curves.png).",
    )
    p.add_argument("--env", default="UTampKitchen-v0", choices=env_ids(), help="env id to train on")
    p.add_argument(
        "--algo",
        default="maskable-ppo",
        choices=TRAIN_ALGOS,
        help="RL algorithm, or bc: behaviour cloning from --demos",
    )
    p.add_argument(
        "--demos",
        metavar="DIR",
        help="with --algo bc: a `utamp demos` dataset folder (macro track, objects)",
    )
    p.add_argument(
        "--grounding",
        default="symbolic",
        choices=GROUNDINGS,
        help="symbolic (fast; the outcome model decides) or physics (MuJoCo)",
    )
    p.add_argument(
        "--masks",
        default="affordances",
        choices=MASK_CHOICES,
        help="what the action mask shows: the U-TAMP-2 preconditions under ground-truth "
        "affordances (default), the geometric ones only, or every action of the scene",
    )
    p.add_argument(
        "--interface",
        default="",
        choices=("grounded", "objects"),
        help="the env's spaces: the suite's ground actions, or object slots with the "
        "slot-transformer policy (maskable-ppo and bc only; the agent then acts on every "
        "suite); default: the env's own (objects for UTampKitchenProcedural-v0, else grounded; "
        "grounded for ppo and dqn)",
    )
    p.add_argument(
        "--init-from",
        metavar="MODEL",
        help="start from this model zip's policy weights (e.g. one from `--algo bc`: fine-tuning)",
    )
    p.add_argument(
        "--num-objects",
        type=int,
        choices=range(2, 6),
        default=None,
        metavar="N",
        help="train on the N-object scenes only (2-5; default all)",
    )
    add_env_option_flags(p)
    p.add_argument("--steps", type=_positive, default=200_000, help="environment steps")
    p.add_argument("--envs", type=_positive, default=8, help="parallel envs")
    p.add_argument("--seed", type=int, default=0, help="seed (of the first run with --seeds)")
    p.add_argument(
        "--seeds", type=_positive, default=1, help="independent runs, seeds S..S+K-1 (default 1)"
    )
    p.add_argument(
        "--executor",
        default="local",
        choices=("local", "ray"),
        help="with --seeds K: train the seeds in local worker processes (default: one after "
        "another in this process) or as parallel Ray tasks (the utamp-gym[ray] extra)",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        help="with --seeds K: local worker processes (default 0: in this process), or the "
        "CPUs of a Ray instance started here (default: all)",
    )
    p.add_argument(
        "--ray-address",
        default=None,
        help="with --executor ray: the cluster to join (default: RAY_ADDRESS, else a local "
        "Ray instance started here)",
    )
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--eval-every", type=_positive, default=10_000, help="steps between evals")
    p.add_argument("--eval-episodes", type=_positive, default=60, help="episodes per eval")
    p.add_argument(
        "--stop-at-target",
        action="store_true",
        help="stop at the first evaluation with >= 90%% success",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_train)
    return p
