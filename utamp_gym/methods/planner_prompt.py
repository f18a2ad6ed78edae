"""The goal the ``vlm-planner`` is asked to reach, written from the scene's `Goal` data, and a
plan written in the vocabulary its answer uses.

A scene without a goal of its own (the paper's suites) keeps the paper's prompt: one tower on
the base (``prompts/planner_goal.txt``). A scene with a goal (procedural-v2) is asked for that
goal (``prompts/planner_task.txt``): its instruction (`utamp_gym.tasks.language`), then each
of its literals in words, in the names the VLM answers with (the detected kinds,
`object_name`; table regions by their slot names), so the text and the planner's goal are
the same data. Objects that share a kind are numbered (``mug-1``, ``mug-2``), and the goal
message then says where each of them stands (`naming_note`). `answer_steps` writes a full
plan in the answer's format (``pick X Y``, ``place X Y``, ``slide X SPACE``), which
`utamp_gym.methods.plan_mapping.map_plan` reads back: the planning benchmark uses it to check
the format offline, with no VLM.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from importlib import resources
from string import Template

from utamp_gym.affordances.facts import Fact
from utamp_gym.methods.plan_mapping import answer_names, map_plan
from utamp_gym.scene.model import Scene
from utamp_gym.suites.procedural_v2.spec import DOMAIN as V2_DOMAIN
from utamp_gym.suites.procedural_v2.spec import SUITE as V2_SUITE
from utamp_gym.symbolic.pddl import Domain, parse_domain, parse_plan, parse_problem
from utamp_gym.symbolic.problem import build_problem, domain_text
from utamp_gym.symbolic.validate import ValidationResult, validate_plan
from utamp_gym.tasks.attributes import region_words
from utamp_gym.tasks.goal import CUSTOM, HAND_EMPTY, Goal, split_literal
from utamp_gym.tasks.language import instruction
from utamp_gym.tasks.templates import parts, template

#: the answer's verbs and, per full action, the parameters naming its two objects
ANSWER_ARGS = {"pick-support": ("?obj1", "?obj2"), "place-support": ("?obj1", "?obj2"),
               "slide-support": ("?obj1", "?space")}  # fmt: skip


def answer_domain(scene: Scene) -> str:
    """The domain an answer for `scene` is read in: its split's labelling domain on
    procedural-v2 (the extended ``utamp2x``), else the paper's ``utamp2``."""
    return V2_DOMAIN if scene.name.startswith(f"{V2_SUITE}/") else "utamp2"


def prompt(name: str, **values: str) -> str:
    """A packaged prompt (``utamp_gym/methods/prompts/<name>.txt``) with ``$values`` filled in."""
    text = resources.files("utamp_gym.methods").joinpath("prompts", f"{name}.txt").read_text()
    return Template(text).substitute(values)


def object_name(scene: Scene, obj: str) -> str:
    """How the answer names `obj`: its kind (type), as the detection question asks, or, if
    other objects of the scene are of that kind, its kind and number (`answer_names`)."""
    return answer_names(scene)[obj]


def naming_note(scene: Scene) -> str:
    """Which object each numbered name is, by where it stands (every object stands on its
    own support, so that tells them apart in the image); "" when no two objects share a kind."""
    names = answer_names(scene)
    numbered = [o for o in scene.objects if names[o.name] != o.type]
    if not numbered:
        return ""
    words = region_words(scene)
    slots = {s.name for s in scene.slots}

    def where(on: str) -> str:
        if on not in slots:
            return f"on the {names[on]}"
        if scene.goal is None:  # the paper's prompt names the table, not its regions
            return f"on the table, in its {words[on]}"
        return f"directly on the table in region {on} ({words[on]})"

    lines = "".join(f"  - {names[o.name]}: the one {where(o.on)}\n" for o in numbered)
    return "\nObjects of the same kind are told apart by a number in their names:\n" + lines


def _name(scene: Scene, x: str) -> str:
    return x if x in {s.name for s in scene.slots} else object_name(scene, x)


def _tower_text(scene: Scene) -> str:
    """The paper's prompt: one tower on the base."""
    base = scene.type_of(scene.tower_base).name
    note, spaces = "", ""
    if scene.spaces:
        names = ", ".join(s.name for s in scene.spaces)
        note = (
            f" The {base} is partly outside the robot's reachable workspace; the free "
            f"space {names} next to it is inside the workspace."
        )
        spaces = f", and {names} for the free space"
    return prompt("planner_goal", base=base, workspace_note=note, space_note=spaces)


def goal_conditions(scene: Scene, goal: Goal) -> list[str]:
    """Each literal of `goal` in words (the hand's first; an object's negated supports in
    one line: it stands on none of them)."""
    slots = {s.name for s in scene.slots}
    lines: list[str] = []
    not_on: dict[str, list[str]] = {}
    for lit in goal.literals:
        positive, a = split_literal(lit)
        _, _, x, y = a.strip("()").split()
        if lit == HAND_EMPTY:
            lines.insert(0, "the hand is empty")
        elif not positive:
            not_on.setdefault(x, []).append(_name(scene, y))
        elif y == "air":
            where = f"table region {x}" if x in slots else _name(scene, x)
            lines.append(f"nothing stands on {where}")
        elif x in slots:
            lines.append(f"{_name(scene, y)} stands directly on the table in region {x}")
        elif y in slots:
            lines.append(f"{_name(scene, x)} stands directly on the table in region {y}")
        else:
            lines.append(f"{_name(scene, x)} stands directly on {_name(scene, y)}")
    for x, supports in not_on.items():
        regions = [y for y in supports if y in slots]
        named = [y for y in supports if y not in slots]
        if len(regions) == len(slots):  # every region: not on the table
            named.append("the table")
        else:
            named += [f"table region {y}" for y in regions]
        lines.append(f"{_name(scene, x)} stands directly on none of: {', '.join(named)}")
    return lines


def goal_text(scene: Scene) -> str:
    """The goal message of the ``vlm-planner`` for `scene` (see the module docstring)."""
    goal = scene.goal
    if goal is None:
        return _tower_text(scene) + naming_note(scene)
    words = region_words(scene)
    regions = ", ".join(f"{s.name} ({words[s.name]})" for s in scene.slots)
    summary = (
        "goal literals given directly"
        if goal.template == CUSTOM
        else "; ".join(template(t).summary for t in parts(goal.template))
    )
    said = "" if goal.template == CUSTOM else f'\n"{instruction(scene, goal)}"\n'
    conditions = "\n".join(f"  - {c}" for c in goal_conditions(scene, goal))
    text = prompt(
        "planner_task",
        instruction=said,
        template=goal.template,
        summary=summary,
        conditions=conditions,
        regions=regions,
        example=_example(scene),
    )
    return text + naming_note(scene)


def _example(scene: Scene) -> str:
    """A format example on this scene's names: its last object picked up and put down in
    the last table region (not a step towards the goal)."""
    o = scene.objects[-1]
    region = next(s.name for s in reversed(scene.slots) if s.name != o.on)
    steps = [f"pick {object_name(scene, o.name)} {_name(scene, o.on)}",
             f"place {object_name(scene, o.name)} {region}"]  # fmt: skip
    return '{"plan": [' + ", ".join(f'"{s}"' for s in steps) + "]}"


@lru_cache(maxsize=4)
def _domain(name: str) -> Domain:
    return parse_domain(domain_text(name), source=f"{name}.pddl")


def answer_steps(scene: Scene, plan: Sequence[str], domain: str = "utamp2") -> list[str]:
    """A full plan (``(pick-support obj2 ...)``) as the answer writes it: ``pick KIND
    SUPPORT``, the table by its region's name (``table`` for a scene without a goal of its
    own, whose prompt names no regions)."""
    actions = _domain(domain).actions
    slots = {s.name for s in scene.slots}
    out = []
    for step in plan:
        name, *args = step.strip("()").split()
        params = [v for v, _ in actions[name].parameters]
        x, y = (args[params.index(v)] for v in ANSWER_ARGS[name])
        verb = name.removesuffix("-support")
        if verb != "slide":
            y = "table" if y in slots and scene.goal is None else _name(scene, y)
        out.append(f"{verb} {_name(scene, x)} {y}")
    return out


def replay_answer(
    scene: Scene, steps: Sequence[object], facts: frozenset[Fact], domain: str = "utamp2"
) -> ValidationResult:
    """Read `steps` back as ``vlm-planner`` does (`map_plan`) and validate the full plan in
    `domain` with the affordance `facts` against the scene's goal (a step the mapper cannot
    map is an invalid result naming it)."""
    mapped = map_plan(scene, steps, domain)
    if not mapped.complete:
        return ValidationResult(valid=False, steps_applied=len(mapped.actions),
                                message=f"not mappable: {mapped.error}")  # fmt: skip
    problem = parse_problem(build_problem(scene, facts, domain).text, source=scene.name)
    return validate_plan(_domain(domain), problem, parse_plan("\n".join(mapped.actions)))


__all__ = [
    "answer_domain",
    "answer_steps",
    "goal_conditions",
    "goal_text",
    "naming_note",
    "object_name",
    "prompt",
    "replay_answer",
]
