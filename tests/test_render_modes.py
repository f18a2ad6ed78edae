"""Render modes and viewers: labelled schematic, rgb_array_list + RecordVideo, human, utamp view.

The window tests run under a private Xvfb display (skipped with a reason without Xvfb) and
assert on a screenshot of it: the table, the tray, the held object's red outline.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import gymnasium as gym
import imageio.v2 as imageio
import numpy as np
import pytest
from xvfb import Display, virtual_display, wait_until

import utamp_gym  # noqa: F401  (registers the envs)
from utamp_gym.agents import PlannerPolicy
from utamp_gym.cli import main
from utamp_gym.env.video import RecordVideo
from utamp_gym.env.viewer import FRAME_RATE, NoDisplayError

SCENE = "pick-place/000"  # board and tray: two macro actions


def _red(img: np.ndarray) -> float:
    """Fraction of pure red pixels (the held object's outline)."""
    r, g, b = np.moveaxis(img.astype(int), -1, 0)
    return float(((r > 180) & (g < 70) & (b < 70)).mean())


def _table(img: np.ndarray) -> float:
    """Fraction of the schematic's table colour (214, 196, 160)."""
    return float((np.abs(img.astype(int) - (214, 196, 160)).max(axis=-1) <= 6).mean())


def _tray(img: np.ndarray) -> float:
    """Fraction of the 3D tray's orange-brown."""
    r, g, b = np.moveaxis(img.astype(int), -1, 0)
    return float(((r > 150) & (r - g > 40) & (g - b > 20)).mean())


def _pick(env: gym.Env[Any, Any]) -> int:
    """The first applicable pick of the board."""
    u = env.unwrapped
    return next(
        int(i)
        for i in np.flatnonzero(u.action_masks())
        if u.action_strings[i].startswith("(pick-support board ")
    )


# ---------------------------------------------------------------- symbolic frames
def test_symbolic_render_is_labelled_and_marks_the_held_object() -> None:
    env = gym.make("UTampKitchen-v0", grounding="symbolic", scene=SCENE, render_mode="rgb_array")
    env.reset(seed=0)
    before = env.render()
    assert before.shape == (480, 480, 3) and before.dtype == np.uint8
    assert _table(before) > 0.2 and _red(before) == 0.0
    env.step(_pick(env))
    after = env.render()
    assert _red(after) > 0.002  # the red outline of the held board
    import matplotlib.figure

    fig = matplotlib.figure.Figure()
    ax = fig.add_axes((0, 0, 1, 1))
    u = env.unwrapped
    u.backend.draw(ax)  # the symbolic backend draws the labelled schematic
    texts = {t.get_text().strip() for t in ax.texts}
    assert {"tray", "board (held)", "slot1", "slot2", "workspace", "robot"} <= texts
    assert fig._suptitle.get_text() == f"{SCENE}: hand holds board"


def test_symbolic_rgb_array_list_gives_one_frame_per_step_and_pops() -> None:
    env = gym.make(
        "UTampKitchen-v0", grounding="symbolic", scene=SCENE, render_mode="rgb_array_list"
    )
    env.reset(seed=0)
    env.step(_pick(env))
    frames = env.render()
    assert isinstance(frames, list) and len(frames) == 2  # reset + one step
    assert env.render() == []
    assert env.metadata["render_fps"] == 2


# ---------------------------------------------------------------- physics frames, video
@pytest.mark.physics
def test_rgb_array_list_and_record_video_give_a_smooth_mp4(tmp_path: Path) -> None:
    def episode(wrapper: type, folder: Path) -> tuple[int, int]:
        env = gym.make(
            "UTampKitchen-v0", scene=SCENE, render_mode="rgb_array_list", render_size=(96, 128)
        )
        assert env.metadata["render_fps"] == FRAME_RATE
        env = wrapper(env, str(folder), episode_trigger=lambda e: True, name_prefix="ep")
        policy = PlannerPolicy(env.unwrapped)
        obs, info = env.reset(seed=0)
        steps, terminated, truncated, reward = 0, False, False, 0.0
        while not (terminated or truncated):
            obs, reward, terminated, truncated, info = env.step(policy(obs, info))
            assert info["failure_reason"] == ""
            steps += 1
        env.close()
        assert reward == 1.0
        (video,) = folder.glob("*.mp4")
        reader = imageio.get_reader(video)
        n_frames = reader.count_frames()
        assert reader.get_meta_data()["fps"] == FRAME_RATE
        reader.close()
        return steps, n_frames

    steps, frames = episode(RecordVideo, tmp_path / "ours")
    assert steps == 2 and frames > 10 * steps  # ~10 frames per simulated second
    steps, frames = episode(gym.wrappers.RecordVideo, tmp_path / "gymnasium")
    assert frames == steps + 1  # Gymnasium 1.4 keeps one frame per step: why ours exists


# ---------------------------------------------------------------- human
def test_human_without_a_display_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(NoDisplayError, match="xvfb-run"):
        gym.make("UTampKitchen-v0", grounding="symbolic", render_mode="human")


HUMAN = textwrap.dedent(
    """
    import sys
    import gymnasium as gym
    import utamp_gym
    from utamp_gym.agents import PlannerPolicy

    env = gym.make("UTampKitchen-v0", scene="{scene}", grounding=sys.argv[1], render_mode="human")
    policy = PlannerPolicy(env.unwrapped)
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(policy(obs, info))
    print(info["action"], flush=True)
    sys.stdin.readline()
    env.close()
    print("closed", flush=True)
    """
).replace("{scene}", SCENE)


def _human_screenshot(display: Display, grounding: str) -> np.ndarray:
    """Run a human-mode env for one step (a pick), screenshot it, close it cleanly."""
    proc = subprocess.Popen(
        [sys.executable, "-c", HUMAN, grounding],
        env=display.env(),
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None and proc.stdin is not None
        line = proc.stdout.readline()
        assert line.startswith("(pick-support board"), proc.stderr.read() if proc.stderr else ""
        img = display.screenshot()
        out, err = proc.communicate("\n", timeout=120)
        assert proc.returncode == 0 and out.strip() == "closed", err
        return img
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


@pytest.mark.physics
def test_human_physics_opens_a_live_mujoco_viewer_under_xvfb() -> None:
    with virtual_display() as display:
        img = _human_screenshot(display, "physics")
    assert _tray(img) > 0.001 and float((img.min(axis=-1) > 200).mean()) > 0.05  # tray, table


def test_human_symbolic_opens_a_labelled_window_under_xvfb() -> None:
    with virtual_display() as display:
        img = _human_screenshot(display, "symbolic")
    assert _table(img) > 0.05 and _red(img) > 0.0005  # the table and the held board's outline


# ---------------------------------------------------------------- utamp view
def test_utamp_view_help(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["view", "--help"])
    assert exit_info.value.code == 0
    out = capsys.readouterr().out
    assert "usage: utamp view" in out and "--symbolic" in out and "--seed" in out


def test_utamp_view_without_a_display_exits_2(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["view", SCENE]) == 2
    assert "needs a display" in capsys.readouterr().err
    assert main(["view", "pick-place/999"]) == 2  # an unknown scene is named first
    assert "unknown scene 'pick-place/999'" in capsys.readouterr().err


@pytest.mark.physics
@pytest.mark.parametrize(
    ("args", "shows"), [([], _tray), (["--symbolic"], _table)], ids=["physics", "symbolic"]
)
def test_utamp_view_opens_the_scene_under_xvfb(args: list[str], shows: Any) -> None:
    code = "import sys; from utamp_gym.cli import main; sys.exit(main(sys.argv[1:]))"
    with virtual_display() as display:
        proc = subprocess.Popen(
            [sys.executable, "-c", code, "view", SCENE, *args],
            env=display.env(),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        try:
            wait_until(
                lambda: shows(display.screenshot()) > 0.001 or proc.poll() is not None,
                180,
                "utamp view's window",
            )
            assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
        finally:
            proc.kill()
            proc.wait()
