"""Kitchen organisation tasks: goals as data (`goal`), the templates that make them
(`templates`), the words for objects and regions (`attributes`), instructions (`language`),
samplers (`sampling`) and success on a measured state (`success`).

Only `goal` is imported here (the scene model and scene files use it); import the other
modules by their names.
"""

from utamp_gym.tasks.goal import CUSTOM, HAND_EMPTY, Goal, goal_holds, unmet

__all__ = ["CUSTOM", "HAND_EMPTY", "Goal", "goal_holds", "unmet"]
