"""The paper's VLM pipelines: ``utamp2-vlm`` (VLM attributes -> rules -> U-TAMP-2) and
``vlm-planner`` (the SayCan proxy: the VLM writes the plan in a simplified vocabulary).

Both show the VLM a rendered image of the scene. ``utamp2-vlm`` asks for the objects'
physical attributes (part shapes, food surfaces, mass, robustness), puts them on the
scene's known geometry and runs the rule parser and Fast Downward. ``vlm-planner``
asks the same detection question (its chain of thought), then for a plan, which is
mapped to full U-TAMP-2 actions (`plan_mapping`). An unusable answer raises
`EndpointError`; the evaluation records its message as the failure.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from utamp_gym.affordances.facts import Fact, Scores, score
from utamp_gym.affordances.rules import derive_affordances
from utamp_gym.affordances.sources import ground_truth_for
from utamp_gym.errors import EndpointError, PlanningTimeout
from utamp_gym.methods.image import render_scene_png
from utamp_gym.methods.plan_mapping import map_plan, split_step
from utamp_gym.methods.planner_prompt import answer_domain, goal_text, prompt
from utamp_gym.methods.vlm_client import Message, VlmClient, extract_json, image_part
from utamp_gym.planning.fast_downward import solve
from utamp_gym.scene.catalogue import ROBUSTNESS, SHAPES, ObjectType
from utamp_gym.scene.geometry import SIDES
from utamp_gym.scene.model import Scene
from utamp_gym.suites.generate import MOVABLES, TRAY
from utamp_gym.symbolic.problem import build_problem, domain_text

VLM_METHODS = ("utamp2-vlm", "vlm-planner")
KINDS = tuple(t for _, t in (*MOVABLES, TRAY))


@dataclass(frozen=True)
class VlmOutcome:
    """What a VLM method produced: a full U-TAMP-2 plan or the reason there is none."""

    solved: bool
    plan: tuple[str, ...]
    planning_time_s: float
    reason: str | None
    scores: Scores | None = None
    facts: frozenset[Fact] | None = None  # detected affordances (utamp2-vlm)
    answers: tuple[str, ...] = field(default=(), repr=False)


def _system_text(scene: Scene) -> str:
    kinds = sorted({*KINDS, *(o.type for o in scene.objects)})
    return prompt(
        "attributes_system",
        kinds=", ".join(kinds),
        robustness=" | ".join(ROBUSTNESS),
        shapes=" | ".join(SHAPES),
    )


def _detection_messages(system: str, png: bytes) -> list[Message]:
    user = [{"type": "text", "text": prompt("attributes_request")}, image_part(png)]
    return [{"role": "system", "content": system}, {"role": "user", "content": user}]


class PlannerTexts(NamedTuple):
    """The text the ``vlm-planner`` sends for a scene (besides the image and the VLM's own
    detection answer): its system message, the detection question and the goal."""

    system: str
    request: str
    goal: str


def planner_texts(scene: Scene) -> PlannerTexts:
    """What `run_vlm_planner` sends for `scene` (the planning benchmark measures it)."""
    system = _system_text(scene) + "\n\n" + prompt("planner_system")
    return PlannerTexts(system, prompt("attributes_request"), goal_text(scene))


def _field(d: Mapping[str, Any], key: str, where: str) -> Any:
    if not isinstance(d, Mapping) or key not in d:
        raise EndpointError(f"answer: {where} has no '{key}'")
    return d[key]


def types_from_answer(data: Mapping[str, Any], scene: Scene) -> list[ObjectType]:
    """The scene's object types with the attributes the VLM reported (table included)."""
    objs = _field(data, "objects", "the answer")
    if not isinstance(objs, list):
        raise EndpointError("answer: 'objects' is not a list")
    by_name = {n: o.type for o in scene.objects for n in (o.name, o.type)}
    reported: dict[str, ObjectType] = {}
    for i, entry in enumerate(objs):
        name = str(_field(entry, "name", f"object #{i + 1}")).strip().lower().replace(" ", "-")
        tname = by_name.get(name)
        if tname is None:
            raise EndpointError(f"answer names unknown object '{name}' (not in this scene)")
        if tname in reported:
            raise EndpointError(f"answer reports '{name}' twice")
        base = scene.catalogue[tname]
        try:
            mass = float(_field(entry, "mass_kg", name))
        except (TypeError, ValueError):
            raise EndpointError(f"answer: mass_kg of '{name}' is not a number") from None
        robustness = str(_field(entry, "robustness", name)).lower()
        if robustness not in ROBUSTNESS or not mass > 0:
            raise EndpointError(
                f"answer: '{name}' needs mass_kg > 0 and robustness in {ROBUSTNESS}"
            )
        parts_in = _field(entry, "parts", name)
        parts = dict(base.parts)
        for side in SIDES:
            attrs = _field(parts_in, side, f"parts of '{name}'")
            shape = str(_field(attrs, "shape", f"part '{side}' of '{name}'")).lower()
            if shape not in SHAPES:
                raise EndpointError(f"answer: shape '{shape}' of '{name}' not in {SHAPES}")
            food = str(attrs.get("food_surface", False)).lower() == "true"
            parts[side] = base.parts[side]._replace(shape=shape, food_surface=food)
        material = str(entry.get("material", base.material))
        reported[tname] = base._replace(
            mass=mass, robustness=robustness, material=material, parts=parts
        )
    missing = sorted({o.name for o in scene.objects if o.type not in reported})
    if missing:
        raise EndpointError(f"answer misses objects: {', '.join(missing)}")
    return [scene.catalogue[scene.table_type], *reported.values()]


def run_utamp2_vlm(
    scene: Scene,
    client: VlmClient,
    *,
    seed: int = 0,
    timeout: float = 30.0,
    image: bytes | None = None,
) -> VlmOutcome:
    """VLM-detected attributes -> rule parser -> U-TAMP-2 -> Fast Downward."""
    png = image if image is not None else render_scene_png(scene, seed)
    start = time.perf_counter()
    answer = client.chat(_detection_messages(_system_text(scene), png))
    facts = derive_affordances(types_from_answer(extract_json(answer), scene))
    scores = score(facts, ground_truth_for(scene))
    problem = build_problem(scene, facts, "utamp2").text
    try:
        result = solve(domain_text("utamp2"), problem, timeout=timeout)
        solved, plan, reason = result.solved, result.plan, result.reason
    except PlanningTimeout as exc:
        solved, plan, reason = False, (), f"planner timed out: {exc}"
    elapsed = time.perf_counter() - start
    return VlmOutcome(solved, plan, elapsed, reason, scores, facts, (answer,))


def run_vlm_planner(
    scene: Scene,
    client: VlmClient,
    *,
    seed: int = 0,
    image: bytes | None = None,
    **_: Any,
) -> VlmOutcome:
    """SayCan proxy: detection question, then the plan, mapped to U-TAMP-2 actions."""
    png = image if image is not None else render_scene_png(scene, seed)
    start = time.perf_counter()
    texts = planner_texts(scene)
    messages = _detection_messages(texts.system, png)
    first = client.chat(messages)
    messages += [
        {"role": "assistant", "content": first},
        {"role": "user", "content": texts.goal},
    ]
    second = client.chat(messages)
    elapsed = time.perf_counter() - start
    steps = _field(extract_json(second), "plan", "the answer")
    if not isinstance(steps, list) or not steps:
        raise EndpointError("answer: 'plan' is not a non-empty list of actions")
    if any(not split_step(s) for s in steps):
        raise EndpointError("answer: 'plan' contains an empty action")
    mapped = map_plan(scene, steps, answer_domain(scene))
    reason = None if mapped.complete else f"plan not mappable: {mapped.error}"
    return VlmOutcome(mapped.complete, mapped.actions, elapsed, reason, answers=(first, second))


RUNNERS: dict[str, Callable[..., VlmOutcome]] = {
    "utamp2-vlm": run_utamp2_vlm,
    "vlm-planner": run_vlm_planner,
}
