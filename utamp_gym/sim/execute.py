"""Deprecated home of the open-loop episode runner: it moved to `utamp_gym.eval.episode`,
where a plan is played by `OpenLoopPolicy` through the env's one loop (this module's own
loop is gone). Importing a name from here still works for one release, with a
`DeprecationWarning` (the new home is imported on use: sim/ depends on nothing above it).
"""

from utamp_gym.deprecated import moved

__getattr__ = moved(
    __name__,
    "utamp_gym.eval.episode",
    ("EpisodeResult", "Execution", "StepRecord", "VIDEO_PERIOD", "VIDEO_SIZE",
     "episode_result", "execute_plan", "run_episode"),
)  # fmt: skip
