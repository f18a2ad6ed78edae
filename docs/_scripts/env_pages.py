"""One documentation page per registered env id, generated from the env itself.

As Gymnasium-Robotics generates its env pages from the env classes, every page here comes from
the code: the id's definition file (``envs/<id>.toml``), the entry point's class docstring
(split at its ``**Section**`` headings), the keyword options of its ``__init__`` (names, types,
defaults) and what `gym.make` actually builds: the spaces, the ``info`` keys of a real reset
and of real steps (a symbolic-grounding episode run by the planner policy to its end, and a
physics reset and step), the action masks, and a picture ``render()`` returned. An id added
to ``envs/`` gets its page with nothing else to write. Nothing here sets a rendering backend:
physics pictures use whatever `render_mode="rgb_array"` picks.
"""

from __future__ import annotations

import importlib
import inspect
import re
import textwrap
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

#: docstring sections shown under their own headings, in this order (the rest follow)
SECTION_ORDER = (
    "Action space",
    "Observation space",
    "Reward",
    "Termination",
    "Info",
    "Options",
    "Closed loop (physics grounding)",
    "Rendering",
    "Version history",
)
#: `masks` values whose action space is reported next to the default's
MASK_MODES = ("affordances", "geometric", "none")
MAX_VALUE_CHARS = 70


@dataclass
class EnvFacts:
    """What one env id is, measured by building and running it."""

    env_id: str
    description: str
    entry_point: str
    max_episode_steps: int
    kwargs: Mapping[str, Any]
    source: str
    docstring: str
    parameters: list[inspect.Parameter]
    action_space: str
    n_actions: int | None  # None: not a Discrete action space
    n_actions_by_masks: dict[str, int]
    observation_space: dict[str, str]
    n_scenes: int
    objects_per_scene: list[int]
    render_modes: list[str]
    info_at_reset: dict[str, Any]
    info_at_step: dict[str, Any]
    info_at_end: dict[str, Any]
    physics_info: dict[str, Any]
    mask_at_reset: tuple[int, int] | None  # (applicable, all); None: no action_masks()
    episode: list[str]
    episode_return: float
    example_actions: list[str]
    sections: dict[str, str] = field(default_factory=dict)
    pictures: dict[str, str] = field(default_factory=dict)
    picture_scene: str = ""
    grounded: bool = True  # the entry point takes ``grounding`` (symbolic and physics)

    @property
    def info_keys(self) -> list[str]:
        """Every ``info`` key seen: at reset, after a step, at an episode's end, in physics."""
        seen: dict[str, None] = {}
        for info in (self.info_at_reset, self.info_at_step, self.info_at_end, self.physics_info):
            seen.update(dict.fromkeys(info))
        return list(seen)


def slug(env_id: str) -> str:
    """An identifier for `env_id` usable in a MyST substitution (``UTampKitchen_v0``)."""
    return re.sub(r"\W", "_", env_id)


def split_docstring(doc: str) -> dict[str, str]:
    """The docstring's intro (key ``""``) and its ``**Title**`` sections, title -> text.

    A section starts at a paragraph that begins with ``**Title**`` (optionally followed by a
    period or a dash); the title is removed from its text.
    """
    text = inspect.cleandoc(doc or "")
    sections: dict[str, list[str]] = {"": []}
    current = ""
    head = re.compile(r"^\*\*(?P<title>[^*]+?)\.?\*\*\s*(?:[–—-]\s*)?(?P<rest>.*)$")
    previous_blank = True
    for line in text.splitlines():
        m = head.match(line) if previous_blank else None
        if m:
            current = m["title"].strip().rstrip(".")
            sections[current] = [m["rest"]] if m["rest"] else []
        else:
            sections[current].append(line)
        previous_blank = not line.strip()
    return {k: "\n".join(v).strip() for k, v in sections.items()}


def space_text(space: gym.Space) -> str:
    """A space on one line: a `Box` with per-entry bounds as its distinct bounds."""
    if isinstance(space, gym.spaces.Box) and not (
        np.all(space.low == space.low.flat[0]) and np.all(space.high == space.high.flat[0])
    ):
        lows = ", ".join(f"{v:g}" for v in np.unique(space.low))
        highs = ", ".join(f"{v:g}" for v in np.unique(space.high))
        return f"Box({space.shape}, {space.dtype}; low in {{{lows}}}, high in {{{highs}}})"
    return str(space)


def _short(value: Any) -> str:
    if isinstance(value, np.ndarray):
        return f"ndarray {value.dtype} {value.shape}"
    text = repr(value)
    return text if len(text) <= MAX_VALUE_CHARS else text[: MAX_VALUE_CHARS - 1] + "…"


def _kind(value: Any) -> str:
    if value is None:
        return "None"
    if isinstance(value, np.ndarray):
        return f"ndarray[{value.dtype}]"
    return type(value).__name__


def _policy(env: gym.Env[Any, Any], seed: int = 0) -> Any:
    """The planner policy for the kitchen envs; a seeded masked-random policy otherwise."""
    from utamp_gym.agents import PlannerPolicy
    from utamp_gym.env.kitchen import UTampKitchenEnv

    base = env.unwrapped
    if isinstance(base, UTampKitchenEnv):
        return PlannerPolicy(base)
    rng = np.random.default_rng(seed)
    env.action_space.seed(seed)

    def act(obs: Any, info: dict[str, Any]) -> Any:
        mask = getattr(base, "action_masks", None)
        if mask is not None:
            return int(rng.choice(np.flatnonzero(mask())))
        return env.action_space.sample()

    return act


def _episode(env: gym.Env[Any, Any]) -> tuple[dict[str, Any], list[dict[str, Any]], float]:
    """(info at reset, info of every step, return) of one episode from ``reset(seed=0)``."""
    policy = _policy(env)
    obs, info = env.reset(seed=0)
    first, infos, total, done = info, [], 0.0, False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy(obs, info))
        infos.append(info)
        total += float(reward)
        done = terminated or truncated
    return first, infos, total


def measure(env_id: str, *, pictures: Path | None = None) -> EnvFacts:
    """Build `env_id` with `gym.make`, run it, and (with `pictures`) render its pictures there.

    Runs an episode from ``reset(seed=0)`` to its end in symbolic grounding (fast) with the
    planner policy, and with `pictures` a physics reset and step, so the ``info`` keys are the
    ones a user sees. Options an entry point does not take (``grounding``, ``masks``) are
    left out, so an id of another env class gets its page too.
    """
    from utamp_gym.env.registry import env_definitions, register_envs

    register_envs()
    definition = next(d for d in env_definitions() if d.id == env_id)
    module, _, name = definition.entry_point.partition(":")
    cls = getattr(importlib.import_module(module), name)
    parameters = [
        p
        for p in inspect.signature(cls.__init__).parameters.values()
        if p.name != "self" and p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)
    ]
    takes = {p.name for p in parameters}
    fast = {"grounding": "symbolic"} if "grounding" in takes else {}
    sym = gym.make(env_id, **fast)
    base = sym.unwrapped
    discrete = isinstance(sym.action_space, gym.spaces.Discrete)
    by_masks = {}
    if discrete and "masks" in takes:
        for masks in MASK_MODES:
            other = gym.make(env_id, **fast, masks=masks)
            by_masks[masks] = int(other.action_space.n)
            other.close()
    info0, infos, total = _episode(sym)
    sym.reset(seed=0)
    mask = base.action_masks() if hasattr(base, "action_masks") else None
    scenes = tuple(getattr(base, "scenes", ()))
    spaces = (
        sym.observation_space.spaces
        if isinstance(sym.observation_space, gym.spaces.Dict)
        else {"(whole observation)": sym.observation_space}
    )
    facts = EnvFacts(
        env_id=env_id,
        description=definition.description,
        entry_point=definition.entry_point,
        max_episode_steps=definition.max_episode_steps,
        kwargs=dict(definition.kwargs),
        source=f"envs/{definition.source.name}",
        docstring=inspect.cleandoc(cls.__doc__ or ""),
        parameters=parameters,
        action_space=space_text(sym.action_space),
        n_actions=int(sym.action_space.n) if discrete else None,
        n_actions_by_masks=by_masks,
        observation_space={k: space_text(v) for k, v in spaces.items()},
        n_scenes=len(scenes),
        objects_per_scene=sorted({s.n_objects for s in scenes}),
        render_modes=list(base.metadata.get("render_modes", [])),
        info_at_reset=info0,
        info_at_step=infos[0] if infos else {},
        info_at_end=infos[-1] if infos else {},
        physics_info={},
        mask_at_reset=None if mask is None else (int(np.count_nonzero(mask)), len(mask)),
        episode=[str(i.get("action")) for i in infos],
        episode_return=total,
        example_actions=list(getattr(base, "action_strings", ())[:3]),
        sections=split_docstring(cls.__doc__ or ""),
        grounded=bool(fast),
    )
    if pictures is not None and "rgb_array" in facts.render_modes:
        pictures.mkdir(parents=True, exist_ok=True)
        if fast:
            schematic = gym.make(env_id, **fast, render_mode="rgb_array")
            schematic.reset(seed=0)
            path = pictures / f"{env_id}-symbolic.png"
            facts.pictures["symbolic"] = _write_png(path, schematic.render())
            schematic.close()
        phys = gym.make(env_id, render_mode="rgb_array")  # the id's default grounding
        pobs, pinfo = phys.reset(seed=0)
        facts.picture_scene = str(pinfo.get("scene", ""))
        facts.pictures["physics"] = _write_png(pictures / f"{env_id}.png", phys.render())
        if phys.observation_space != sym.observation_space or (
            phys.action_space != sym.action_space
        ):
            raise AssertionError(f"{env_id}: the spaces differ between groundings")
        if fast:
            *_, pinfo = phys.step(_policy(phys)(pobs, pinfo))
            facts.physics_info = pinfo
        phys.close()
    sym.close()
    return facts


def _write_png(path: Path, frame: Any) -> str:
    import imageio.v3 as iio

    iio.imwrite(path, np.asarray(frame, np.uint8))
    return path.name


def _rst(text: str) -> list[str]:
    """A docstring part (reStructuredText) as a MyST block."""
    return ["```{eval-rst}", textwrap.dedent(text).strip(), "```", ""]


def _info_table(facts: EnvFacts) -> list[str]:
    mode = " (symbolic)" if facts.grounded else ""
    rows = [
        f"| key | at `reset` | after a step{mode} | at the episode's end{mode} "
        "| after a step (physics) |",
        "|---|---|---|---|---|",
    ]

    def cell(info: Mapping[str, Any], key: str) -> str:
        if key not in info:
            return "–"
        value = info[key]
        return f"{_kind(value)}: `{_short(value)}`".replace("|", "\\|")

    for key in facts.info_keys:
        rows.append(
            f"| `{key}` | {cell(facts.info_at_reset, key)} | {cell(facts.info_at_step, key)} "
            f"| {cell(facts.info_at_end, key)} | {cell(facts.physics_info, key)} |"
        )
    return rows


def _default(env_default: Any, kwargs: Mapping[str, Any], name: str) -> str:
    if name in kwargs:
        return f"`{kwargs[name]!r}` (this id)"
    if env_default is inspect.Parameter.empty:
        return "required"
    return f"`{env_default!r}`"


def page(facts: EnvFacts) -> str:
    """The env page as MyST Markdown."""
    s = facts.sections
    env_id = facts.env_id
    out = [
        f"<!-- generated by docs/_scripts/env_pages.py from {facts.source} and "
        f"{facts.entry_point}: edit those, not this file -->",
        f"(env-{env_id})=",
        f"# {env_id}",
        "",
        facts.description + ".",
        "",
    ]
    for kind, caption in (
        ("physics", f"`render()` after `reset(seed=0)` (scene `{facts.picture_scene}`), physics"),
        ("symbolic", "the same in symbolic grounding: the labelled schematic"),
    ):
        if kind in facts.pictures:
            out += [
                f"```{{figure}} {facts.pictures[kind]}",
                ":width: 45%",
                "",
                caption,
                "```",
                "",
            ]
    counts = facts.objects_per_scene
    objects = f"{counts[0]}–{counts[-1]}" if len(counts) > 1 else "".join(map(str, counts))
    keys = ", ".join(f"`{k}`" for k in facts.observation_space)
    out += [
        "| | |",
        "|---|---|",
        f'| make | `gym.make("{env_id}")` (after `import utamp_gym`) |',
        f"| entry point | `{facts.entry_point}` |",
        f"| definition | `{facts.source}` |",
    ]
    if facts.n_scenes:
        out.append(f"| scenes | {facts.n_scenes} ({objects} objects each) |")
    out += [
        f"| action space | `{facts.action_space}` |",
        f"| observation space | {keys} |",
        f"| max_episode_steps | {facts.max_episode_steps} |",
        f"| render modes | {', '.join(f'`{m}`' for m in facts.render_modes)} |",
        "",
    ]
    if s.get(""):
        out += ["## Description", "", *_rst(s[""])]

    out += [
        "## Action space",
        "",
        f'`gym.make("{env_id}").action_space` is `{facts.action_space}`.',
        "",
    ]
    if facts.n_actions_by_masks:
        out += [
            'Its size depends on the `masks` option (the action ids of `masks="affordances"` '
            "are the same in all):",
            "",
            "| `masks` | action space |",
            "|---|---|",
            *(f'| `"{m}"` | `Discrete({n})` |' for m, n in facts.n_actions_by_masks.items()),
            "",
        ]
    if facts.example_actions:
        out += [
            "The first action ids (`env.unwrapped.action_strings`):",
            "",
            *(f"- `{i}`: `{a}`" for i, a in enumerate(facts.example_actions)),
            "",
        ]
    if s.get("Action space"):
        out += _rst(s["Action space"])
    if facts.mask_at_reset is not None:
        applicable, total = facts.mask_at_reset
        out += [
            "## Action masks",
            "",
            f"`env.unwrapped.action_masks()` is a boolean array of length {total}; after "
            f"`reset(seed=0)` {applicable} actions are applicable. `MaskablePPO` (sb3-contrib) "
            "reads `action_masks()`."
            + (
                " The `masks` option chooses what the mask allows (see *Options*)."
                if facts.n_actions_by_masks
                else ""
            ),
            "",
        ]
    out += ["## Observation space", "", "| key | space |", "|---|---|"]
    out += [f"| `{k}` | `{v}` |" for k, v in facts.observation_space.items()]
    out.append("")
    if s.get("Observation space"):
        out += _rst(s["Observation space"])
    for title in ("Reward", "Termination"):
        if s.get(title):
            out += [f"## {title}", "", *_rst(s[title])]
    who = "A planner-policy episode" if facts.example_actions else "An episode"
    out += [
        f"{who}{' of symbolic grounding' if facts.grounded else ''} after `reset(seed=0)` "
        f"({len(facts.episode)} steps, return {facts.episode_return:g}):",
        "",
        *(f"{i + 1}. `{a}`" for i, a in enumerate(facts.episode)),
        "",
        "## Info",
        "",
        "The keys of `info`, as returned by a real `reset(seed=0)` and real steps of "
        "this id (values shortened):",
        "",
        *_info_table(facts),
        "",
    ]
    if s.get("Info"):
        out += _rst(s["Info"])
    out += [
        "## Options",
        "",
        f'Keyword arguments of `gym.make("{env_id}", ...)` (the parameters of '
        f"`{facts.entry_point.replace(':', '.')}`; the id's own defaults come from "
        f"`{facts.source}`):",
        "",
        "| option | type | default |",
        "|---|---|---|",
    ]
    for p in facts.parameters:
        annotation = "" if p.annotation is inspect.Parameter.empty else str(p.annotation)
        annotation = annotation.replace("|", "\\|")
        out.append(f"| `{p.name}` | `{annotation}` | {_default(p.default, facts.kwargs, p.name)} |")
    out.append("")
    if s.get("Options"):
        out += _rst(s["Options"])
    shown = {"", "Action space", "Observation space", "Reward", "Termination", "Info", "Options"}
    rest = [t for t in SECTION_ORDER if t in s and t not in shown]
    rest += [t for t in s if t not in shown and t not in SECTION_ORDER]
    for title in rest:
        if s[title]:
            out += [f"## {title}", "", *_rst(s[title])]
    return "\n".join(out)


def index(all_facts: Iterable[EnvFacts]) -> str:
    """The env index: one row and one toctree entry per id."""
    all_facts = list(all_facts)
    out = [
        "<!-- generated by docs/_scripts/env_pages.py from utamp_gym.env.registry.env_ids() -->",
        "# Environments",
        "",
        "Every id registered by `import utamp_gym` (one definition file per id in `envs/`). "
        "Each page is generated from the env itself.",
        "",
        "| id | scenes | action space | max_episode_steps | description |",
        "|---|---|---|---|---|",
    ]
    for f in all_facts:
        out.append(
            f"| [{f.env_id}](env-{f.env_id}) | {f.n_scenes} | `{f.action_space}` | "
            f"{f.max_episode_steps} | {f.description} |"
        )
    out += ["", "```{toctree}", ":hidden:", "", *(f.env_id for f in all_facts), "```", ""]
    return "\n".join(out)
