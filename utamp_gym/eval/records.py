"""Result rows of an evaluation sweep and the crash-safe `results.csv` they live in.

One row per scene × method × seed (× grounding × noise). Rows are appended whole,
each followed by flush + fsync, so a killed sweep leaves at most a torn last line,
which `ResultsFile` drops when it opens the file again; rewrites (header upgrades,
the final sort) go through a temporary file and `os.replace`.
"""

from __future__ import annotations

import csv
import hashlib
import io
import os
from collections.abc import Iterable
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

from utamp_gym.eval.stages import ATTRIBUTE_COLUMNS

GROUNDINGS = ("physics", "symbolic")
PLAN_SEPARATOR = " ; "
#: measured with a clock: they differ between two runs of one task, nothing else may
TIMING_COLUMNS = ("planning_time_s", "execution_time_s", "wall_time_s")

#: scene, method, seed, grounding, noise, closed_loop, disturbance, pose_noise, perception
Key = tuple[str, str, int, str, str, bool, str, str, str]
KEY_FIELDS = (
    "scene",
    "method",
    "seed",
    "grounding",
    "noise",
    "closed_loop",
    "disturbance",
    "pose_noise",
    "perception",
)
#: how the robot estimates object poses in physics (env option ``perception``; the same as
#: `utamp_gym.backend.PERCEPTION_MODES`, kept here so that reading results needs no numpy)
PERCEPTION_MODES = ("gaussian", "rgbd")
DEFAULT_PERCEPTION = "gaussian"


def noise_label(noise: float | None) -> str:
    """A number's part of a row key: ``""`` for None (not applicable), else ``f"{p:g}"``."""
    return "" if noise is None else f"{noise:g}"


def row_key(
    scene: str,
    method: str,
    seed: int,
    grounding: str,
    noise: float | None,
    closed_loop: bool,
    disturbance: float,
    pose_noise: float | None,
    perception: str = DEFAULT_PERCEPTION,
) -> Key:
    """The identity of one run: two rows with equal keys are the same run (the default
    perception is written as ``""``, so rows from before the option keep their keys)."""
    return (
        scene,
        method,
        seed,
        grounding,
        noise_label(noise),
        closed_loop,
        noise_label(disturbance),
        noise_label(pose_noise),
        "" if perception == DEFAULT_PERCEPTION else perception,
    )


def key_text(key: Key) -> str:
    """A run key as ``field=value`` pairs, for messages."""
    return ", ".join(f"{n}={_fmt(v)}" for n, v in zip(KEY_FIELDS, key, strict=True))


def key_shard(key: Key, n: int) -> int:
    """The shard (0..n-1) of a run: a stable hash of its key (SHA-256, not the salted hash());
    a default (empty) perception is left out, so older sweeps keep their shards."""
    values = key[:-1] if key[-1] == "" else key
    text = "\x1f".join(_fmt(v) for v in values)
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "big") % n


class RunIdentity:
    """What names one run: the `key` shared by a task (`EvalTask`) and its row."""

    scene: str
    method: str
    seed: int
    grounding: str
    noise: float | None
    closed_loop: bool
    disturbance: float
    pose_noise: float | None
    perception: str

    @property
    def key(self) -> Key:
        return row_key(
            self.scene,
            self.method,
            self.seed,
            self.grounding,
            self.noise,
            self.closed_loop,
            self.disturbance,
            self.pose_noise,
            self.perception,
        )


@dataclass(frozen=True)
class ResultRow(RunIdentity):
    """One evaluated run. Times in seconds; `plan` holds the actions joined by ``" ; "``.

    `valid_gt` is whether the plan is valid under the ground-truth U-TAMP-2 model (None
    without a plan); `crashed` marks rows recorded for a run that raised or whose worker
    process died. `closed_loop`: the planner policy acted in the env and replanned from the
    perceived state (`n_replans` times) instead of executing one plan open-loop;
    `disturbance`: the probability of an injected fault per macro step (`n_faults` happened);
    `pose_noise`: the robot's pose-estimation noise (m; None in symbolic grounding);
    `perception`: where the robot's object poses come from in physics (``gaussian``: the
    true pose plus `pose_noise`; ``rgbd``: the cameras). Stage-wise scoring
    (`utamp_gym.eval.stages`): `failure_stage` names the stage that lost a failed run, the
    ``acc_*`` columns give the per-attribute accuracy of detected attributes (None for
    methods that detect none).
    """

    scene: str
    suite: str
    n_objects: int
    method: str
    seed: int
    grounding: str
    noise: float | None
    solved: bool
    success: bool
    failure_reason: str
    plan_length: int
    planning_time_s: float | None
    execution_time_s: float
    wall_time_s: float
    affordance_precision: float | None
    affordance_recall: float | None
    affordance_f1: float | None
    valid_gt: bool | None = None
    crashed: bool = False
    plan: str = ""
    closed_loop: bool = False
    disturbance: float = 0.0
    pose_noise: float | None = None
    n_faults: int = 0
    n_replans: int = 0
    perception: str = DEFAULT_PERCEPTION
    failure_stage: str = ""
    acc_body: float | None = None
    acc_members: float | None = None
    acc_member_size: float | None = None
    acc_shape: float | None = None
    acc_surface: float | None = None
    acc_height: float | None = None
    acc_food: float | None = None
    acc_material: float | None = None
    acc_mass: float | None = None
    acc_mass_class: float | None = None
    acc_robustness: float | None = None
    n_weighings: int = 0  # closed loop, interactive perception: weighing lifts
    n_looks: int = 0  # closed loop, interactive perception: extra looks

    def to_csv(self) -> dict[str, str]:
        return {k: _fmt(v) for k, v in asdict(self).items()}

    def outcome(self) -> dict[str, str]:
        """The row as written to CSV without the wall-clock columns: equal for equal runs."""
        return {k: v for k, v in self.to_csv().items() if k not in TIMING_COLUMNS}

    def differences(self, other: ResultRow) -> list[str]:
        """The columns, wall-clock ones excepted, in which `other` differs from this row."""
        mine, theirs = self.outcome(), other.outcome()
        return [k for k in mine if mine[k] != theirs[k]]

    @classmethod
    def from_csv(cls, d: dict[str, str]) -> ResultRow:
        return cls(
            scene=d["scene"],
            suite=d["suite"],
            n_objects=int(d["n_objects"]),
            method=d["method"],
            seed=int(d["seed"]),
            grounding=d["grounding"],
            noise=_opt_float(d.get("noise", "")),
            solved=_bool(d["solved"]),
            success=_bool(d["success"]),
            failure_reason=d.get("failure_reason", ""),
            plan_length=int(d.get("plan_length") or 0),
            planning_time_s=_opt_float(d.get("planning_time_s", "")),
            execution_time_s=float(d.get("execution_time_s") or 0.0),
            wall_time_s=float(d.get("wall_time_s") or 0.0),
            affordance_precision=_opt_float(d.get("affordance_precision", "")),
            affordance_recall=_opt_float(d.get("affordance_recall", "")),
            affordance_f1=_opt_float(d.get("affordance_f1", "")),
            valid_gt=None if d.get("valid_gt", "") == "" else _bool(d["valid_gt"]),
            crashed=_bool(d.get("crashed") or "false"),
            plan=d.get("plan", ""),
            closed_loop=_bool(d.get("closed_loop") or "false"),
            disturbance=float(d.get("disturbance") or 0.0),
            pose_noise=_opt_float(d.get("pose_noise", "")),
            n_faults=int(d.get("n_faults") or 0),
            n_replans=int(d.get("n_replans") or 0),
            perception=d.get("perception") or DEFAULT_PERCEPTION,
            failure_stage=d.get("failure_stage", ""),
            **{c: _opt_float(d.get(c, "")) for c in ATTRIBUTE_COLUMNS},
            n_weighings=int(d.get("n_weighings") or 0),
            n_looks=int(d.get("n_looks") or 0),
        )


COLUMNS: tuple[str, ...] = tuple(f.name for f in fields(ResultRow))


def _fmt(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _bool(s: str) -> bool:
    return s.strip().lower() in ("true", "1", "yes")


def _opt_float(s: str | None) -> float | None:
    return None if s is None or s.strip() == "" else float(s)


def _csv_line(row: ResultRow) -> str:
    buf = io.StringIO()
    csv.DictWriter(buf, COLUMNS, lineterminator="\n").writerow(row.to_csv())
    return buf.getvalue()


def _write_atomic(path: Path, rows: Iterable[ResultRow]) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    with tmp.open("w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, COLUMNS, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow(r.to_csv())
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


class ResultsFile:
    """`results.csv` of one output directory: read on open, appended row by row."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.rows: dict[Key, ResultRow] = {}
        self._load()

    def _load(self) -> None:
        if not self.path.exists():
            _write_atomic(self.path, [])
            return
        rows, clean = _parse(self.path.read_text(encoding="utf-8"))
        self.rows = {r.key: r for r in rows}
        if not clean:  # torn last line or an older header: rewrite what was readable
            _write_atomic(self.path, self.rows.values())

    def __contains__(self, key: object) -> bool:
        return key in self.rows

    def append(self, row: ResultRow) -> None:
        """Append one complete row and make it durable before returning."""
        line = _csv_line(row)
        with self.path.open("a", newline="", encoding="utf-8") as f:
            f.write(line)
            f.flush()
            os.fsync(f.fileno())
        self.rows[row.key] = row

    def sort(self) -> None:
        """Rewrite the file in a stable order (atomically)."""
        write_rows(self.path, self.rows.values())


def write_rows(path: str | Path, rows: Iterable[ResultRow]) -> None:
    """Write a whole results file (header + `rows` in the stable order), atomically."""
    _write_atomic(Path(path), sorted(rows, key=_order))


def _order(r: ResultRow) -> tuple[Any, ...]:
    return (
        r.suite,
        r.grounding,
        r.method,
        r.noise or 0.0,
        r.closed_loop,
        r.disturbance,
        r.pose_noise or 0.0,
        r.perception,
        r.scene,
        r.seed,
    )


def _parse(text: str) -> tuple[list[ResultRow], bool]:
    """Readable rows of a CSV text, and whether the text was clean (complete, current)."""
    clean = not text or text.endswith("\n")
    if not clean:  # a killed writer: drop the incomplete last line
        text = text[: text.rfind("\n") + 1]
    reader = csv.DictReader(io.StringIO(text))
    clean = clean and tuple(reader.fieldnames or COLUMNS) == COLUMNS
    rows = []
    for d in reader:
        try:
            rows.append(ResultRow.from_csv(d))
        except (KeyError, ValueError, TypeError):
            clean = False  # unreadable row: it is dropped and simply run again
    return rows, clean


def read_rows(path: str | Path) -> list[ResultRow]:
    """All readable rows of a results file (read only; the file is not repaired)."""
    return _parse(Path(path).read_text(encoding="utf-8"))[0]
