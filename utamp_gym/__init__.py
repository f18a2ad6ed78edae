"""utamp_gym: a Gymnasium suite for U-TAMP-2 kitchen-table organisation on a MuJoCo Panda.

Layers, each in its own sub-package:
scene -> affordances -> perception -> symbolic -> planning -> robot/sim -> env -> eval / rl
(`utamp_gym.backend` is the contract between sim and env).
"""

__version__ = "0.1.0"

# Explicit registration of the envs defined in `envs/` (one file per env id), so that
# `import utamp_gym` then `gymnasium.make("UTampKitchen-v0")` works.
from utamp_gym.env.registry import register_envs

register_envs()
