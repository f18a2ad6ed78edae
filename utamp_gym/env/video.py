"""`RecordVideo`: Gymnasium's video recorder, keeping every frame of an ``rgb_array_list`` env.

Why: a macro action simulates seconds, so one frame per step makes a slide show. With
``render_mode="rgb_array_list"`` the physics env renders 10 frames per simulated second
(`utamp_gym.env.viewer`), but Gymnasium's `gymnasium.wrappers.RecordVideo` (1.4) keeps only
the last frame of each list it fetches after a step. This subclass keeps them all; with
``render_mode="rgb_array"`` it behaves exactly like Gymnasium's. Writing the MP4 needs
moviepy (``pip install 'utamp-gym[video]'``).

Outside a wrapper, ``gymnasium.utils.save_video.save_video(env.render(), ...)`` at the end
of an episode saves the same frames (``render()`` returns all since the reset).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
from gymnasium.error import DependencyNotInstalled

from utamp_gym.extras import MissingExtraError, require


class RecordVideo(gym.wrappers.RecordVideo):
    """`gymnasium.wrappers.RecordVideo` that records every frame of a frame list."""

    def __init__(self, env: gym.Env[Any, Any], video_folder: str, **kwargs: Any) -> None:
        try:  # before Gymnasium's wrapper makes the folder and finds moviepy missing
            require("RecordVideo", "video")
        except MissingExtraError as exc:
            raise DependencyNotInstalled(str(exc)) from exc
        super().__init__(env, video_folder, **kwargs)

    def _capture_frame(self) -> None:
        if self.env.render_mode != "rgb_array_list":
            super()._capture_frame()
            return
        assert self.recording, "Cannot capture a frame, recording wasn't started."
        frames = self.env.render()
        if not isinstance(frames, list):
            self.stop_recording()
            raise TypeError(f"render() of an rgb_array_list env returned {type(frames)}")
        self.recorded_frames += frames
        self.render_history += frames  # what `render()` of this wrapper hands back
