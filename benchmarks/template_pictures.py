"""Before/after pictures of each procedural-v2 goal template: one scene per template, the
initial scene and the final state after the labelling planner's plan is executed in MuJoCo
physics, with its instruction and goal literals (issue #38 item 6).

The scene of a template is a deterministic pick: the first achievable scene of that template
in the order of `SPLIT_ORDER` (test splits first; ``restack`` lives in ``hard`` only) whose
plan, planned with the split's labelling method (`spec.LABEL_METHOD`), succeeds when played
open loop in physics (`execute_plan`, seed ``--seed``); after `--tries` failed candidates
the first candidate is shown with its failure. Both pictures come from the episode's own
simulator (overview camera, `PhysicsBackend.render`): the initial one after the reset the
run starts from, the final one after its last step. Writes ``<out>/<template>.png`` (palette
PNGs, each with the commit and command) and ``<out>.md`` with the commit and command.

    python benchmarks/template_pictures.py [--out docs/results/template_pictures]
        [--size 320 240] [--seed 0] [--tries 3]
"""

from __future__ import annotations

import argparse
import io
from pathlib import Path
from typing import Any

import numpy as np

from utamp_gym.agents.runs import execute_plan, open_loop_env
from utamp_gym.planning.methods import plan_scene
from utamp_gym.provenance import png_metadata, provenance, write_markdown
from utamp_gym.seeding import run_seed
from utamp_gym.suites.procedural_v2 import split_scenes
from utamp_gym.suites.procedural_v2.spec import LABEL_METHOD
from utamp_gym.tasks.language import instruction

SPLIT_ORDER = ("test-tasks", "test-instances", "test-families", "test-count", "hard")
TEMPLATE_ORDER = (
    "tower", "subset-on", "two-stacks", "put-on", "clear", "in-region", "unstack", "restack",
    "sort", "put-on+clear", "in-region+in-region", "clear+in-region", "put-on+in-region",
)  # fmt: skip
MAX_BYTES = 60_000  # each picture at most


def candidates(template: str) -> list[Any]:
    """The achievable scenes of `template`, in the deterministic order of the pick."""
    return [
        s for split in SPLIT_ORDER for s in split_scenes(split)
        if s.template == template and s.achievable
    ]  # fmt: skip


def _png(pixels: np.ndarray, prov: dict[str, str]) -> bytes:
    """A palette PNG (256 colours) of `pixels` with the provenance text chunks."""
    from PIL import Image, PngImagePlugin  # matplotlib's own dependency

    info = PngImagePlugin.PngInfo()
    for k, v in png_metadata(prov).items():
        info.add_text(k, v)
    image = Image.fromarray(np.ascontiguousarray(pixels)).quantize(256)
    buf = io.BytesIO()
    image.save(buf, format="PNG", optimize=True, pnginfo=info)
    return buf.getvalue()


def picture(scene: Any, seed: int, size: tuple[int, int]) -> dict[str, Any]:
    """Plan `scene`, play the plan in physics and render before and after."""
    outcome = plan_scene(scene, LABEL_METHOD)
    env = open_loop_env(scene.name)
    try:
        world = run_seed(scene.name, seed)  # the reset `execute_plan` starts from
        env.reset(seed=world, options={"world_seed": world})
        before = env.backend.render(*size)
        ex = execute_plan(scene.name, outcome.plan, seed, env=env)
        after = env.backend.render(*size)
    finally:
        env.close()
    return {"outcome": outcome, "execution": ex, "before": before, "after": after}


def _section(template: str, s: Any, run: dict[str, Any], rel: str, tried: int) -> list[str]:
    scene, goal = s.scene, s.scene.goal
    ex, plan = run["execution"], run["outcome"].plan
    said = instruction(scene, goal)
    if ex.success:
        result = f"executed in physics: success ({len(plan)} actions)"
    else:
        result = f"executed in physics: **failed** ({ex.failure_reason})"
    pick = "" if tried == 1 else f" (candidate {tried}: earlier ones failed in physics)"
    literals = ", ".join(f"`{lit}`" for lit in goal.literals)
    return [
        f"### {template}",
        "",
        f'`{scene.name}`{pick}: *"{said}"*',
        "",
        f"![{template}: initial scene]({rel}/{template}-before.png) "
        f"![{template}: after the plan]({rel}/{template}-after.png)",
        "",
        f"Left: the initial scene. Right: the final state, {result}. Goal literals: {literals}.",
        "",
    ]


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/results/template_pictures")
    ap.add_argument("--size", type=int, nargs=2, default=[320, 240], metavar=("W", "H"))
    ap.add_argument("--seed", type=int, default=0, help="the physics run's seed")
    ap.add_argument("--tries", type=int, default=3, help="candidates tried per template")
    ap.add_argument("--templates", nargs="+", default=list(TEMPLATE_ORDER))
    return ap


def main() -> int:
    args = build_parser().parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    prov = provenance()
    size = (args.size[0], args.size[1])
    lines = [
        "Each goal template of procedural-v2 on one scene: the initial scene and the final "
        f"state after the plan of {LABEL_METHOD} (the splits' labelling method) is played open "
        f"loop in MuJoCo physics (seed {args.seed}, overview camera, {size[0]}x{size[1]}). "
        "The scene is the first achievable one of its template in the order "
        f"{', '.join(SPLIT_ORDER)} whose physics run succeeds (at most {args.tries} tried).",
        "",
    ]
    n_ok = 0
    for template in args.templates:
        scenes = candidates(template)
        if not scenes:
            raise SystemExit(f"no achievable procedural-v2 scene of template {template!r}")
        chosen, tried = None, 0
        for tried, s in enumerate(scenes[: args.tries], 1):
            run = picture(s.scene, args.seed, size)
            if chosen is None or run["execution"].success:
                chosen = (s, run, tried)
            if run["execution"].success:
                break
        assert chosen is not None
        s, run, tried = chosen
        n_ok += run["execution"].success
        for when in ("before", "after"):
            data = _png(run[when], prov)
            if len(data) > MAX_BYTES:
                raise SystemExit(f"{template}-{when}.png: {len(data)} bytes > {MAX_BYTES}")
            (out / f"{template}-{when}.png").write_bytes(data)
        lines += _section(template, s, run, out.name, tried)
        print(f"{template}: {s.scene.name} success={run['execution'].success}", flush=True)
    lines.insert(2, f"Physics succeeded on {n_ok} of {len(args.templates)} templates' scenes.\n")
    write_markdown(f"{args.out}.md", "\n".join(lines), prov)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
