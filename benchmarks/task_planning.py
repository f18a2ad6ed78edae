"""Plan length, planning time and nodes expanded per goal template on procedural-v2 scenes,
for several Fast Downward search configurations side by side.

Plans every achievable goal of a sample of each split (every ``--step``-th scene, every scene
of ``hard``; the generator's first ``--seeds`` seeds when the split file does not hold the
split yet) with a planner method (default: the split file's labeller, `spec.LABEL_METHOD`)
under each ``--searches`` configuration, and prints per (configuration, template): scenes,
solved, median and p95 planning time (s), median / max plan length (actions), median / max
nodes Fast Downward expanded; then the same for the hard suite alone, and the worst median
planning time per template against the 1 s target. Each scene is planned cold (a new
planner per scene and configuration).

Then per template the ``vlm-planner`` prompt format, measured offline (no VLM is run): the
characters and words of the text the method sends (`utamp_gym.methods.vlm.planner_texts`:
system message, detection question and the goal written from the scene's `Goal`; the image
and the VLM's own detection answer not counted), the goal message alone, the actions the
answer must hold (the shortest reference plan of the configurations), and whether that plan
written in the answer's format (`planner_prompt.answer_steps`) reads back with the method's
own parser to a valid plan reaching the goal (`planner_prompt.replay_answer`). Writes
``<out>.md`` and ``<out>.json`` with the commit and the command.

    python benchmarks/task_planning.py [--splits train test-tasks hard] [--step 10]
        [--searches astar-blind lama-first] [--out docs/results/task_planning]
"""

from __future__ import annotations

import argparse
import statistics
from collections import defaultdict
from typing import Any

from utamp_gym.affordances.sources import affordances_for
from utamp_gym.methods.planner_prompt import answer_steps, replay_answer
from utamp_gym.methods.vlm import planner_texts
from utamp_gym.planning.downward import PlanResult
from utamp_gym.planning.fast_downward import SEARCH_CONFIGS
from utamp_gym.planning.methods import method_spec, plan_scene
from utamp_gym.planning.state_planner import StatePlanner
from utamp_gym.provenance import provenance, write_json, write_markdown
from utamp_gym.suites.procedural.spec import NoLayout
from utamp_gym.suites.procedural_v2 import available_splits, generate_scene, split_scenes
from utamp_gym.suites.procedural_v2.spec import LABEL_METHOD, SPLITS

TARGET_S = 1.0  # the planner's median per template stays within this


class _Recording(StatePlanner):
    """A state planner that keeps its last result (for the nodes Fast Downward expanded)."""

    last: PlanResult | None = None

    def plan(self, *args: Any, **kwargs: Any) -> PlanResult:
        self.last = super().plan(*args, **kwargs)
        return self.last


def _sample(split: str, step: int, seeds: int) -> list[tuple[Any, str, bool]]:
    """(scene, template, achievable or not known) of the split's sample."""
    if split in available_splits():
        return [(g.scene, g.template, g.achievable) for g in split_scenes(split)[::step]]
    out = []
    for seed in range(seeds):
        try:
            g = generate_scene(split, seed)
        except NoLayout:
            continue
        out.append((g.scene, g.template, True))
    return out


def _p95(xs: list[float]) -> float:
    xs = sorted(xs)
    return xs[min(len(xs) - 1, round(0.95 * (len(xs) - 1)))]


def _table(title: str, rows: dict[tuple[str, str], list[dict[str, Any]]]) -> list[str]:
    lines = [
        title,
        "",
        "| search | template | scenes | solved | median s | p95 s | median length | "
        "max length | median expanded | max expanded |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (search, template), rs in sorted(rows.items()):
        times = [r["time_s"] for r in rs]
        lengths = [r["plan_length"] for r in rs if r["solved"]]
        nodes = [r["expanded"] for r in rs if r["expanded"] is not None]
        lines.append(
            f"| {search} | {template} | {len(rs)} | {sum(r['solved'] for r in rs)} | "
            f"{statistics.median(times):.3f} | {_p95(times):.3f} | "
            f"{statistics.median(lengths) if lengths else '-'} | {max(lengths, default='-')} | "
            f"{statistics.median(nodes) if nodes else '-'} | {max(nodes, default='-')} |"
        )
    return lines


def _prompt_row(scene: Any, plans: list[tuple[str, ...]], method: str) -> dict[str, Any]:
    """The vlm-planner prompt's measures on one scene (`plans`: its solved reference plans)."""
    spec = method_spec(method)
    texts = planner_texts(scene)
    sent = "\n".join(texts)
    row: dict[str, Any] = {
        "scene": scene.name, "chars": len(sent), "words": len(sent.split()),
        "goal_chars": len(texts.goal), "actions": None, "valid": None,
    }  # fmt: skip
    if plans:
        plan = min(plans, key=len)
        facts, _ = affordances_for(scene, spec.affordances, None, domain=spec.domain)
        steps = answer_steps(scene, plan, spec.domain)
        row |= {
            "actions": len(plan),
            "valid": replay_answer(scene, steps, facts, spec.domain).valid,
        }
    return row


def _prompt_table(title: str, rows: dict[str, list[dict[str, Any]]]) -> list[str]:
    lines = [
        title,
        "",
        "| template | scenes | median chars | max chars | median words | median goal chars | "
        "median actions | max actions | read back valid |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for template, rs in sorted(rows.items()):
        chars = [r["chars"] for r in rs]
        actions = [r["actions"] for r in rs if r["actions"] is not None]
        checked = [r for r in rs if r["valid"] is not None]
        lines.append(
            f"| {template} | {len(rs)} | {statistics.median(chars):.0f} | {max(chars)} | "
            f"{statistics.median(r['words'] for r in rs):.0f} | "
            f"{statistics.median(r['goal_chars'] for r in rs):.0f} | "
            f"{statistics.median(actions) if actions else '-'} | {max(actions, default='-')} | "
            f"{sum(r['valid'] for r in checked)}/{len(checked)} |"
        )
    return lines


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--splits", nargs="+", choices=SPLITS, default=list(SPLITS))
    ap.add_argument("--step", type=int, default=10, help="every STEP-th scene (hard: all)")
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--method", default=LABEL_METHOD)
    ap.add_argument("--searches", nargs="+", choices=SEARCH_CONFIGS,
                    default=["astar-blind", "lama-first"])  # fmt: skip
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--out", default="docs/results/task_planning")
    return ap


def main() -> int:
    args = build_parser().parse_args()
    domain = method_spec(args.method).domain
    rows: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    hard: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    prompts: dict[str, list[dict[str, Any]]] = defaultdict(list)
    hard_prompts: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for split in args.splits:
        step = 1 if split == "hard" else args.step
        for scene, template, achievable in _sample(split, step, args.seeds):
            if not achievable:
                continue
            plans = []
            for search in args.searches:
                planner = _Recording(domain, search=search, timeout=args.timeout)
                out = plan_scene(scene, args.method, timeout=args.timeout, planner=planner)
                row = {"scene": scene.name, "solved": out.solved, "time_s": out.planning_time_s,
                       "plan_length": out.plan_length,
                       "expanded": planner.last.expanded if planner.last else None}  # fmt: skip
                rows[search, template].append(row)
                if split == "hard":
                    hard[search, template].append(row)
                if out.solved:
                    plans.append(out.plan)
            prompt_row = _prompt_row(scene, plans, args.method)
            prompts[template].append(prompt_row)
            if split == "hard":
                hard_prompts[template].append(prompt_row)
    lines = _table(
        f"Planning per template ({args.method}; splits {', '.join(args.splits)}: achievable "
        f"goals of every {args.step}th scene, every hard scene)",
        rows,
    )
    if hard:
        lines += ["", *_table("The hard suite alone (procedural-v2/hard)", hard)]
    worst = max(statistics.median(r["time_s"] for r in rs) for rs in rows.values())
    verdict = "met" if worst <= TARGET_S else "NOT met"
    lines += ["", f"Worst median planning time over (search, template): {worst:.3f} s "
              f"(target <= {TARGET_S:.0f} s: {verdict})"]  # fmt: skip
    lines += ["", *_prompt_table(
        "The vlm-planner prompt format per template (measured offline: **no VLM was run**; "
        "chars and words: the text the method sends, without the image and the VLM's own "
        "detection answer; actions: the shortest reference plan above, which the answer must "
        "hold; read back valid: that plan written in the answer's format and read back by the "
        "method's own parser is a valid plan reaching the goal)", prompts)]  # fmt: skip
    if hard_prompts:
        lines += ["", *_prompt_table("The vlm-planner prompt format, hard suite alone",
                                     hard_prompts)]  # fmt: skip
    text = "\n".join(lines) + "\n"
    print(text)
    prov = provenance()
    write_markdown(f"{args.out}.md", text, prov)
    write_json(
        f"{args.out}.json",
        {"rows": {f"{s}/{t}": rs for (s, t), rs in sorted(rows.items())},
         "vlm_planner_prompt": dict(sorted(prompts.items())),
         "worst_median_s": worst, "args": vars(args)},
    )  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
