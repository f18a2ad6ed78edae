"""utamp_gym: a Gymnasium suite for U-TAMP-2 kitchen-table organisation on a MuJoCo Panda.

Layers, each in its own sub-package:
scene -> affordances -> symbolic -> planning -> robot/sim -> env -> eval / rl.
"""

__version__ = "0.1.0"
