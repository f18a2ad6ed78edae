"""utamp_gym: a Gymnasium suite for U-TAMP-2 kitchen-table organisation on a MuJoCo Panda.

Layers, each in its own sub-package:
scene -> contract -> affordances -> perception -> symbolic -> planning -> robot/sim -> env ->
methods -> eval / rl. `contract` holds the types the simulator and perception exchange, and
`utamp_gym.backend` the protocol between a backend and the env; `sim` never imports
`perception` (the env's backend composes them: `utamp_gym.grounding`).
"""

import itertools
import os
import sys

__version__ = "0.1.0"


def _started_as_utamp_command() -> bool:
    """True in a process started as the `utamp` command (its console script, or
    ``python -m utamp_gym.cli``): `utamp_gym.cli.main` registers the envs itself, for the
    subcommands that use them, so that ``utamp plan`` never imports Gymnasium.

    Decided from the interpreter's own command line (`sys.orig_argv`), not from `sys.argv`
    alone: the worker processes of ``utamp eval`` / ``utamp train`` (multiprocessing's spawn)
    inherit the parent's `sys.argv`, whose ``argv[0]`` ends in ``utamp``, but were started as
    ``python -c ...``; they import this package to unpickle their task and must register.
    """
    argv = getattr(sys, "orig_argv", [])
    script = sys.argv[0] if sys.argv else ""
    if os.path.basename(script) == "utamp" and script in argv[1:]:
        return True
    return any(a == "-m" and b == "utamp_gym.cli" for a, b in itertools.pairwise(argv))


# Explicit registration of the envs defined in `envs/` (one file per env id), so that
# `import utamp_gym` then `gymnasium.make("UTampKitchen-v0")` works.
if not _started_as_utamp_command():
    from utamp_gym.env.registry import register_envs

    register_envs()
