"""What a saved model needs to act again: its env, read from and written into the model zip.

Why inside the zip: a model is only usable on the env it was trained on (the same env id,
mask mode, observation entries and action ids). `utamp train` writes `ModelMeta` as the zip
member `META_NAME` next to stable-baselines3's own members (which SB3 ignores on load), so the
file carries it wherever it is copied, checkpoints included. `utamp eval --methods rl:PATH`
reads it to build the evaluation env and rejects a mismatch (`check_model`) with a clear
error. Only the standard library is used here: the eval CLI validates models without torch.
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from utamp_gym.errors import UtampError

META_NAME = "utamp_env.json"
META_VERSION = 1


class ModelError(UtampError, ValueError):
    """A saved model is missing, unreadable, or does not fit the env it should act on."""


@dataclass(frozen=True)
class ModelMeta:
    """The env a model was trained on and the spaces it expects.

    `env_options` are the `gym.make` keyword options that define the task for the agent
    (``masks``; see `utamp_gym.env.kitchen`); `obs_keys` the observation entries it reads;
    `n_actions` / `n_fluents` the sizes of its action space and ``symbolic`` observation.
    """

    env_id: str
    suite: str
    algo: str
    obs_keys: tuple[str, ...]
    n_actions: int
    n_fluents: int
    env_options: Mapping[str, Any] = field(default_factory=dict)
    trained_grounding: str = "symbolic"
    version: int = META_VERSION

    @property
    def masks(self) -> str:
        return str(self.env_options.get("masks", "affordances"))

    @property
    def env_kwargs(self) -> dict[str, Any]:
        """`env_options` with the interface explicit: a model saved without one is grounded
        (the env id's own default may be the objects interface)."""
        return {"interface": "grounded", **self.env_options}

    def to_json(self) -> dict[str, Any]:
        data = asdict(self)
        data["obs_keys"], data["env_options"] = list(self.obs_keys), dict(self.env_options)
        return data

    @staticmethod
    def from_json(data: Mapping[str, Any], source: str) -> ModelMeta:
        try:
            return ModelMeta(
                env_id=str(data["env_id"]),
                suite=str(data["suite"]),
                algo=str(data["algo"]),
                obs_keys=tuple(data["obs_keys"]),
                n_actions=int(data["n_actions"]),
                n_fluents=int(data["n_fluents"]),
                env_options=dict(data.get("env_options", {})),
                trained_grounding=str(data.get("trained_grounding", "symbolic")),
                version=int(data.get("version", META_VERSION)),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelError(f"{source}: malformed {META_NAME} ({exc!r})") from None


def write_meta(path: str | Path, meta: ModelMeta) -> None:
    """Add (or replace) `META_NAME` in the model zip at `path`."""
    path = Path(path)
    text = json.dumps(meta.to_json(), indent=2) + "\n"
    with zipfile.ZipFile(path) as z:
        present = META_NAME in z.namelist()
    if not present:
        with zipfile.ZipFile(path, "a", compression=zipfile.ZIP_DEFLATED) as z:
            z.writestr(META_NAME, text)
        return
    tmp = path.with_name(f".{path.name}.tmp")  # zip members cannot be replaced in place
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            if item.filename != META_NAME:
                dst.writestr(item, src.read(item.filename))
        dst.writestr(META_NAME, text)
    tmp.replace(path)


def read_meta(path: str | Path) -> ModelMeta:
    """The `ModelMeta` of the model zip at `path`; `ModelError` names the file and what is
    wrong (missing, not a zip, saved without metadata)."""
    path = Path(path)
    if not path.is_file():
        raise ModelError(f"model file {path} does not exist")
    try:
        with zipfile.ZipFile(path) as z:
            if META_NAME not in z.namelist():
                raise ModelError(
                    f"{path} has no {META_NAME}: it was not saved by `utamp train` (or by an "
                    "older version), so its env is unknown; retrain it with `utamp train`"
                )
            data = json.loads(z.read(META_NAME))
    except (OSError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
        raise ModelError(f"{path}: not a readable model zip ({exc})") from None
    return ModelMeta.from_json(data, str(path))


def interface_of(keys: Iterable[str]) -> str:
    """The env option ``interface`` an observation (or a model's observation space) with
    these entries comes from: "grounded" (``symbolic``), "objects" (``attributes``, ``held``,
    ...), else "unknown"."""
    keys = set(keys)
    if "symbolic" in keys:
        return "grounded"
    return "objects" if {"attributes", "held"} <= keys else "unknown"


def trained_entries(keys: Sequence[str], observation: Mapping[str, Any]) -> dict[str, Any]:
    """The entries `keys` of `observation`; `ModelError` naming both interfaces when some are
    missing (a model of one env interface given the other's observation)."""
    missing = [k for k in keys if k not in observation]
    if not missing:
        return {k: observation[k] for k in keys}
    want, have = interface_of(keys), interface_of(observation)
    lacks = ", ".join(f"'{k}'" for k in missing)
    if want == have or "unknown" in (want, have):
        which = "" if want == "unknown" else f" (the {want} interface)"
        raise ModelError(
            f"the model reads the observation entries {', '.join(keys)}{which}, but this "
            f"observation lacks {lacks}"
        )
    raise ModelError(
        f"the model was trained on the {want} interface, but this observation comes from the "
        f"{have} interface (it lacks {lacks}): make the env with interface='{want}', e.g. "
        f"gym.make(..., interface='{want}'), or use a model trained with "
        f"interface='{have}' (utamp train --interface {have})"
    )


def check_model(
    meta: ModelMeta, path: str | Path, *, suite: str | None = None, same_actions: bool = False
) -> None:
    """Raise `ModelError` if the model cannot act on the suite's env (`suite` None: any; an
    agent of the objects interface acts on every suite, a grounded one on every suite whose
    action universe is its own: `same_actions`, e.g. the splits of procedural-v1)."""
    if meta.env_options.get("interface") == "objects" or same_actions:
        return
    if suite is not None and meta.suite != suite:
        raise ModelError(
            f"{path} was trained on {meta.env_id} (suite '{meta.suite}'), whose action ids "
            f"mean other actions than the '{suite}' suite's: evaluate it on '{meta.suite}', "
            "or train with --interface objects (one policy for every suite)"
        )


def check_spaces(meta: ModelMeta, path: str | Path, n_actions: int, n_fluents: int) -> None:
    """Raise `ModelError` if the env's action or ``symbolic`` sizes differ from training."""
    if (meta.n_actions, meta.n_fluents) != (n_actions, n_fluents):
        raise ModelError(
            f"{path} expects {meta.n_actions} actions and {meta.n_fluents} symbolic atoms "
            f"({meta.env_id}, masks '{meta.masks}'), but the env has {n_actions} and "
            f"{n_fluents}: its action universe changed since the model was trained"
        )
