"""Saved agents and training seeds in worker processes, run as a user runs them: the `utamp`
console script in a subprocess (its workers inherit ``sys.argv[0] == ".../utamp"``), with the
default executor, ``--workers 2`` and ``--executor ray``; a sweep whose runs crash exits 1."""

from __future__ import annotations

import csv
import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("sb3_contrib")

from utamp_gym.cli import main
from utamp_gym.rl.train import train

UTAMP = Path(sys.executable).with_name("utamp")


def _utamp(args: str, cwd: Path, **env: str) -> subprocess.CompletedProcess[str]:
    """The installed `utamp` command, as a user starts it (no test-only environment)."""
    return subprocess.run(
        [str(UTAMP), *shlex.split(args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=900,
        env={**os.environ, **env},
    )


def _rows(out: Path) -> list[dict[str, str]]:
    with (out / "results.csv").open() as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("agent")
    train(
        algo="maskable-ppo", masks="geometric", num_objects=2, steps=512, n_envs=2, seed=0,
        out=out, eval_every=512, eval_episodes=2, progress=False,
    )  # fmt: skip
    return out / "model.zip"


def test_started_as_utamp_command_only_in_the_command_itself() -> None:
    """The check reads the interpreter's own command line: a spawned worker of `utamp`
    (argv[0] inherited, started as ``python -c``) registers the envs on import."""
    code = (
        "import sys; sys.argv = ['/x/bin/utamp', 'eval']; import utamp_gym, gymnasium; "
        "print(utamp_gym._started_as_utamp_command(), 'UTampKitchen-v0' in gymnasium.registry)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"]


@pytest.mark.parametrize("executor", ["", "--workers 2", "--executor ray --workers 2"])
def test_utamp_eval_runs_rl_agents_in_workers(model: Path, tmp_path: Path, executor: str) -> None:
    if "ray" in executor:
        pytest.importorskip("ray")
    out = tmp_path / "eval"
    args = (
        f"eval --suite pick-place --methods utamp2-gt,rl:{model} --grounding symbolic "
        f"--limit 3 {executor} --quiet --out {out}"
    )
    done = _utamp(args, tmp_path, RAY_ADDRESS="")
    assert done.returncode == 0, done.stderr
    rows = _rows(out)
    assert len(rows) == 6
    agent = [r for r in rows if r["method"] == f"rl:{model}"]
    assert len(agent) == 3
    assert all(r["crashed"] == "false" and int(r["plan_length"]) >= 1 for r in agent), agent
    assert "crashed" not in done.stderr


def test_utamp_train_two_seeds_in_two_local_workers(tmp_path: Path) -> None:
    args = (
        "train --algo maskable-ppo --masks geometric --num-objects 2 --steps 256 --envs 2 "
        "--seeds 2 --executor local --workers 2 --eval-every 256 --eval-episodes 2 "
        f"--no-progress --out {tmp_path / 'runs'}"
    )
    done = _utamp(args, tmp_path)
    assert done.returncode == 0, done.stderr
    for seed in (0, 1):
        assert (tmp_path / "runs" / f"seed_{seed}" / "model.zip").is_file()
    assert (tmp_path / "runs" / "aggregate.json").is_file()


def test_a_sweep_with_crashed_runs_exits_1_and_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import utamp_gym.eval.runner as runner

    real = runner._run

    def crash_on_002(task, start, envs):  # type: ignore[no-untyped-def]
        if task.scene == "pick-place/002":
            raise RuntimeError("boom")
        return real(task, start, envs)

    monkeypatch.setattr(runner, "_run", crash_on_002)
    args = (
        "eval --suite pick-place --methods utamp2-gt --grounding symbolic --limit 3 "
        f"--workers 0 --quiet --out {tmp_path}"
    )
    assert main(shlex.split(args)) == 1
    err = capsys.readouterr().err
    assert "1 of 3 run(s) crashed" in err and "RuntimeError: boom" in err
    # fixed: the crashed run (only it) runs again on resume, and the sweep is complete
    monkeypatch.setattr(runner, "_run", real)
    assert main(shlex.split(args)) == 0
    assert "1 run(s), 2 resumed" in capsys.readouterr().out
    assert [r["crashed"] for r in _rows(tmp_path)] == ["false"] * 3
