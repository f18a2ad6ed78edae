"""Env ids from definition files: one TOML file per id in `envs/` (adding an env = adding a file).

`register_envs()` reads them and calls `gymnasium.register` explicitly, one flat call per id
as in Gymnasium's own ``gymnasium/envs/__init__.py``; importing this module registers
nothing. A definition file holds::

    id = "UTampKitchen-v0"                                   # must equal the file name
    entry_point = "utamp_gym.env.kitchen:UTampKitchenEnv"   # optional, this is the default
    max_episode_steps = 100                                  # Gymnasium's TimeLimit
    description = "..."                                      # optional
    [kwargs]                                                 # default keyword options
    suite = "pick-place"
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import gymnasium
import tomli  # see utamp_gym.scene.fields

from utamp_gym.errors import UtampError
from utamp_gym.resources import envs_dir

DEFAULT_ENTRY_POINT = "utamp_gym.env.kitchen:UTampKitchenEnv"
_KEYS = {"id", "entry_point", "max_episode_steps", "description", "kwargs"}


class EnvDefinitionError(UtampError, ValueError):
    """An env definition file is malformed; the message names the file and the field."""


@dataclass(frozen=True)
class EnvDefinition:
    """One registered env id, as read from its file."""

    id: str
    entry_point: str
    max_episode_steps: int
    kwargs: Mapping[str, Any]
    description: str
    source: Path


def load_definition(path: str | Path) -> EnvDefinition:
    """Read and check one definition file."""
    path = Path(path)

    def fail(message: str) -> EnvDefinitionError:
        return EnvDefinitionError(f"{path}: {message}")

    try:
        data = tomli.loads(path.read_text())
    except tomli.TOMLDecodeError as exc:
        raise fail(f"invalid TOML: {exc}") from exc
    unknown = sorted(set(data) - _KEYS)
    if unknown:
        raise fail(f"unknown field(s) {', '.join(unknown)}; valid: {', '.join(sorted(_KEYS))}")
    env_id = data.get("id")
    if env_id != path.stem:
        raise fail(f"field 'id' must equal the file name '{path.stem}', got {env_id!r}")
    steps = data.get("max_episode_steps")
    if isinstance(steps, bool) or not isinstance(steps, int) or steps <= 0:
        raise fail(f"field 'max_episode_steps' must be a positive integer, got {steps!r}")
    entry = data.get("entry_point", DEFAULT_ENTRY_POINT)
    if not isinstance(entry, str) or entry.count(":") != 1:
        raise fail(f"field 'entry_point' must be 'module:Class', got {entry!r}")
    kwargs = data.get("kwargs", {})
    if not isinstance(kwargs, dict):
        raise fail("field 'kwargs' must be a table of keyword options")
    return EnvDefinition(
        id=env_id,
        entry_point=entry,
        max_episode_steps=steps,
        kwargs=MappingProxyType(kwargs),
        description=str(data.get("description", "")),
        source=path,
    )


def env_definitions(folder: str | Path | None = None) -> tuple[EnvDefinition, ...]:
    """Every definition in `folder` (default: the packaged `envs/`), sorted by id."""
    root = Path(folder) if folder is not None else envs_dir()
    return tuple(sorted((load_definition(p) for p in root.glob("*.toml")), key=lambda d: d.id))


def env_ids(folder: str | Path | None = None) -> tuple[str, ...]:
    return tuple(d.id for d in env_definitions(folder))


def register_envs(folder: str | Path | None = None) -> tuple[str, ...]:
    """Register every definition with Gymnasium; returns the ids.

    Calling it again is harmless: an id already registered with the same entry point, kwargs
    and step limit is left alone (a changed one is re-registered, and Gymnasium warns).
    """
    ids = []
    for d in env_definitions(folder):
        kwargs = dict(d.kwargs)
        old = gymnasium.registry.get(d.id)
        same = old is not None and (
            old.entry_point == d.entry_point
            and old.kwargs == kwargs
            and old.max_episode_steps == d.max_episode_steps
        )
        if not same:
            gymnasium.register(
                id=d.id,
                entry_point=d.entry_point,
                kwargs=kwargs,
                max_episode_steps=d.max_episode_steps,
            )
        ids.append(d.id)
    return tuple(ids)
