"""utamp_gym: a Gymnasium suite for U-TAMP-2 kitchen-table organisation on a MuJoCo Panda.

Layers, each in its own sub-package:
scene -> affordances -> perception -> symbolic -> planning -> robot/sim -> env -> eval / rl
(`utamp_gym.backend` is the contract between sim and env).
"""

import itertools
import os
import sys

__version__ = "0.1.0"


def _started_as_utamp_command() -> bool:
    """True in a process started as the `utamp` command (its console script, or
    ``python -m utamp_gym.cli``): `utamp_gym.cli.main` registers the envs itself, for the
    subcommands that use them, so that ``utamp plan`` never imports Gymnasium."""
    if os.path.basename(sys.argv[0]) == "utamp":
        return True
    argv = getattr(sys, "orig_argv", [])
    return any(a == "-m" and b == "utamp_gym.cli" for a, b in itertools.pairwise(argv))


# Explicit registration of the envs defined in `envs/` (one file per env id), so that
# `import utamp_gym` then `gymnasium.make("UTampKitchen-v0")` works.
if not _started_as_utamp_command():
    from utamp_gym.env.registry import register_envs

    register_envs()
