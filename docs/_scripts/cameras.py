"""The camera table of docs/perception.md, from `utamp_gym.sim.cameras` (never typed in)."""

from __future__ import annotations

import math


def cameras_table() -> str:
    """Markdown: every camera's mount, position, target, field of view, image sizes and the
    intrinsics at each size."""
    from utamp_gym.sim.cameras import (
        ACTING_SIZE,
        ACTING_VIEWS,
        SCENE_CAMERAS,
        SURVEY_SIZE,
        SURVEY_VIEWS,
        WRIST_CAMERA,
        WRIST_SIZE,
        intrinsics,
    )

    def fmt(v: tuple[float, ...]) -> str:
        return "(" + ", ".join(f"{x:.2f}" for x in v) + ")"

    def k(fovy: float, size: tuple[int, int]) -> str:
        i = intrinsics(fovy, *size)
        return f"{size[0]} x {size[1]}: f = {i.fx:.1f} px, c = ({i.cx:.1f}, {i.cy:.1f})"

    lines = [
        "| camera | mounted on | position (m) | looks at (m) | vertical FOV | used in | "
        "intrinsics (pinhole, square pixels) |",
        "|---|---|---|---|---|---|---|",
    ]
    for cam in (*SCENE_CAMERAS, WRIST_CAMERA):
        uses, sizes = [], []
        if cam.name in SURVEY_VIEWS:
            uses.append("survey (attributes)")
            sizes.append(SURVEY_SIZE)
        if cam.name in ACTING_VIEWS:
            uses.append("every look while acting (poses)")
            sizes.append(ACTING_SIZE)
        if cam is WRIST_CAMERA:
            uses.append("every look and the close looks (poses)")
            sizes.append(WRIST_SIZE)
        mount = "world" if cam.body is None else f"`{cam.body}` (hand frame)"
        lines.append(
            f"| `{cam.name}` | {mount} | {fmt(cam.pos)} | {fmt(cam.target)} | "
            f"{cam.fovy:.0f} deg | {'; '.join(uses)} | {'; '.join(k(cam.fovy, s) for s in sizes)} |"
        )
    lines += [
        "",
        "Every camera looks along its target direction with the world's z axis (the wrist "
        "camera: the hand's x axis) up in the image; depth is metric along the optical "
        f"axis. Focal length f = (height / 2) / tan(FOV / 2); the survey's {SURVEY_SIZE[0]} x "
        f"{SURVEY_SIZE[1]} pixels see about "
        f"{2 * 1.1 * math.tan(math.radians(SCENE_CAMERAS[0].fovy) / 2) / SURVEY_SIZE[1] * 1000:.1f}"
        " mm per pixel at 1.1 m.",
    ]
    return "\n".join(lines) + "\n"
