"""Optional extras stay optional: the core imports none of them, and a missing extra is named.

These run with or without the ``dm`` extra (``make test-mujoco4`` runs them without it).
"""

from __future__ import annotations

import contextlib
import importlib.util
import re
import shutil
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest
from procs import user_env

from utamp_gym.errors import UtampError
from utamp_gym.extras import EXTRAS, MissingExtraError, missing_module, require

ROOT = Path(__file__).resolve().parents[1]


def _run(code: str) -> str:
    out = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        env=user_env(),
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    return out.stdout


def test_import_utamp_gym_does_not_import_dm_control_or_dm_env() -> None:
    code = "import sys, utamp_gym; print('dm_control' in sys.modules, 'dm_env' in sys.modules)"
    assert _run(code).split() == ["False", "False"]


def test_utamp_gym_dm_without_dm_control_names_the_extra() -> None:
    """Without dm_control (really missing, or hidden here), `utamp_gym.dm` says what to install."""
    hide = (
        "" if importlib.util.find_spec("dm_control") is None else 'sys.modules["dm_control"] = None'
    )
    out = _run(
        f"""
        import sys
        {hide}
        try:
            import utamp_gym.dm
        except ModuleNotFoundError as exc:
            print(exc.name, "|", exc)
        """
    )
    assert out.startswith("dm_control |") and "pip install 'utamp-gym[dm]'" in out


# --------------------------------------------------------- a missing extra, before any work
def _hide(monkeypatch: pytest.MonkeyPatch, extra: str) -> None:
    """`extra` looks uninstalled: ``import``/``find_spec`` of its modules find nothing."""
    for module in EXTRAS[extra]:
        monkeypatch.setitem(sys.modules, module, None)


#: every (command, option) that needs an extra: the extra hidden, and the command line
#: (``{out}``: a folder that must not be created, ``{root}``: an existing folder)
NEEDS = {
    "utamp train": ("rl", ["train", "--steps", "64", "--no-progress", "--out", "{out}"]),
    "utamp train --algo bc": (
        "data", ["train", "--algo", "bc", "--demos", "{root}", "--out", "{out}"],
    ),
    "utamp train --executor ray": (
        "ray", ["train", "--seeds", "2", "--executor", "ray", "--out", "{out}"],
    ),
    "utamp eval --methods rl:PATH": (
        "rl", ["eval", "--suite", "pick-place", "--methods", "utamp1,rl:{root}/model.zip",
               "--out", "{out}"],
    ),
    "utamp eval --executor ray": (
        "ray", ["eval", "--suite", "pick-place", "--executor", "ray", "--out", "{out}"],
    ),
    "utamp demos": (
        "data", ["demos", "--suite", "pick-place", "--episodes", "40", "--grounding", "physics",
                 "--out", "{out}"],
    ),
    "utamp demos --track low-level": (
        "dm", ["demos", "--suite", "pick-place", "--track", "low-level", "--out", "{out}"],
    ),
    "utamp demos --executor ray": (
        "ray", ["demos", "--suite", "pick-place", "--executor", "ray", "--out", "{out}"],
    ),
    "utamp demos export-lerobot": (
        "data", ["demos", "export-lerobot", "--root", "{root}", "--dataset", "utamp/x-v0",
                 "--out", "{out}/lerobot"],
    ),
}  # fmt: skip


@pytest.mark.parametrize("needed_by", NEEDS, ids=NEEDS.keys())
def test_a_missing_extra_exits_2_with_one_line_before_any_work(
    needed_by: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from utamp_gym.cli import main

    extra, argv = NEEDS[needed_by]
    _hide(monkeypatch, extra)
    # an option's extra is checked after its command's (`utamp train --executor ray`: after
    # `utamp train`'s rl), which may be missing too where this runs (`make test-mujoco4`)
    command = needed_by.split(" --")[0]
    if command in NEEDS and command != needed_by and missing_module(NEEDS[command][0]):
        needed_by, extra = command, NEEDS[command][0]
    out = tmp_path / "out"
    assert main([a.format(out=out, root=tmp_path) for a in argv]) == 2
    captured = capsys.readouterr()
    assert captured.err == (
        f"utamp: error: {needed_by} needs the '{extra}' extra (no module named "
        f"'{missing_module(extra)}'); install it: pip install 'utamp-gym[{extra}]'\n"
    )
    assert captured.out == ""
    assert not out.exists()  # not even the output folder: nothing ran


def test_every_extra_check_of_the_cli_is_tested() -> None:
    """Each ``require("utamp ...", ...)`` in the package is a case of `NEEDS`."""
    checks = set()
    for path in (ROOT / "utamp_gym").rglob("*.py"):
        checks |= set(re.findall(r"\brequire\(\s*\"(utamp [^\"]+)\"", path.read_text()))
    assert len(checks) >= len(NEEDS) - 1 and checks == set(NEEDS), checks ^ set(NEEDS)


def test_require_names_the_first_missing_module(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(EXTRAS, "video", ("numpy", "utamp_no_such_module", "also_missing"))
    with pytest.raises(MissingExtraError) as exc:
        require("RecordVideo", "dev", "video")
    assert exc.value.name == "utamp_no_such_module" and exc.value.extra == "video"
    assert isinstance(exc.value, ModuleNotFoundError) and isinstance(exc.value, UtampError)
    assert str(exc.value) == (
        "RecordVideo needs the 'video' extra (no module named 'utamp_no_such_module'); "
        "install it: pip install 'utamp-gym[video]'"
    )
    monkeypatch.setitem(EXTRAS, "video", ("numpy",))
    require("RecordVideo", "video")  # all there: nothing raised


def test_record_video_without_moviepy_names_the_extra_before_making_its_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gymnasium as gym
    from gymnasium.error import DependencyNotInstalled

    import utamp_gym  # noqa: F401  (registers the env ids)
    from utamp_gym.env.video import RecordVideo

    _hide(monkeypatch, "video")
    env = gym.make("UTampKitchen-v0", grounding="symbolic", render_mode="rgb_array")
    with pytest.raises(DependencyNotInstalled, match=re.escape("pip install 'utamp-gym[video]'")):
        RecordVideo(env, str(tmp_path / "videos"))
    assert not (tmp_path / "videos").exists()
    env.close()


def test_zoo_without_its_extra_exits_2_with_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from utamp_gym.rl import zoo

    _hide(monkeypatch, "zoo")
    assert zoo.main(["evaluate", "--run", "logs/maskable-ppo/UTampKitchen-v0_1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "needs the 'zoo' extra" in err, err
    assert "pip install 'utamp-gym[zoo]'" in err


def test_the_extras_are_pyprojects_and_their_modules_come_from_them() -> None:
    """`EXTRAS` names every extra of pyproject.toml, and each of its modules (where installed)
    belongs to a distribution that extra requires (or one of them does: minari[hdf5] h5py)."""
    from importlib.metadata import PackageNotFoundError, packages_distributions, requires

    def names(requirements: list[str]) -> set[str]:
        return {re.sub(r"[-_.]+", "-", re.match(r"[\w.-]+", r)[0]).lower() for r in requirements}

    def norm(name: str) -> str:
        return next(iter(names([name])))

    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    declared = declared["optional-dependencies"]
    assert set(EXTRAS) == set(declared)
    installed = packages_distributions()
    for extra, modules in EXTRAS.items():
        requirements = names(declared[extra])
        for direct in list(requirements):
            with contextlib.suppress(PackageNotFoundError):  # not installed here
                requirements |= names(requires(direct) or [])
        for module in modules:
            for dist in installed.get(module, []):
                assert norm(dist) in requirements, (extra, module, dist)


# ------------------------------------------------- the install the Makefile and the pages name
CPU_INDEX = "https://download.pytorch.org/whl/cpu"
INSTALL_PAGES = ("README.md", "docs/getting-started.md", "docs/dependencies.md")


def _make_venv(*overrides: str) -> list[str]:
    """The commands `make venv` runs (printed, not run: ``-n``; ``-B``: even if built)."""
    out = subprocess.run(
        ["make", "-C", str(ROOT), "-n", "-B", "--no-print-directory", "venv", *overrides],
        capture_output=True, text=True, check=True, timeout=60,
    )  # fmt: skip
    return [line.rstrip() for line in out.stdout.splitlines()]


def _torch_default() -> str:
    """The Makefile's ``TORCH ?= ...`` (checking it declares ``TORCH_INDEX`` too)."""
    makefile = (ROOT / "Makefile").read_text()
    default = re.search(r"^TORCH\s*\?=\s*(\S+)$", makefile, re.M)
    assert default and re.search(r"^TORCH_INDEX\s*\?=", makefile, re.M)
    return default[1]


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_make_venv_installs_torch_first_from_the_index_given() -> None:
    torch = _torch_default()
    commands = _make_venv()
    first = [line for line in commands if "pip install" in line and "torch" in line]
    assert first == [f'.venv/bin/pip install --quiet "{torch}"'], commands  # no other index
    extras = next(line for line in commands if "pip install" in line and "-e" in line)
    assert commands.index(first[0]) < commands.index(extras)  # the extras find torch installed
    cpu = _make_venv(f"TORCH_INDEX={CPU_INDEX}")
    assert f'.venv/bin/pip install --quiet "{torch}" --index-url "{CPU_INDEX}"' in cpu, cpu
    assert '.venv/bin/pip install --quiet "torch==2.14.1"' in _make_venv("TORCH=torch==2.14.1")


def test_the_pages_say_what_make_venv_installs_and_how_to_get_the_cpu_build() -> None:
    """The torch the pages name is the Makefile's default; each says that with stock pip it
    is the CUDA build and gives the CPU index; they list the extras `make venv` installs."""
    torch = _torch_default()
    installed = re.search(
        r'pip install --quiet -e "\.\[([\w,]+)\]"', (ROOT / "Makefile").read_text()
    )
    assert installed
    extras = installed[1].split(",")
    assert sorted(extras) == sorted(EXTRAS)  # every extra of pyproject.toml
    for page in INSTALL_PAGES:
        text = " ".join((ROOT / page).read_text().split())
        assert f"`{torch}`" in text, page
        assert "CUDA" in text and "stock settings" in text, page
        assert f"make venv TORCH_INDEX={CPU_INDEX}" in text, page
        for claim in ("never pulls a CUDA", "a **CPU** torch", "CPU build of torch"):
            assert claim not in text, (page, claim)  # what pip does not do with stock settings
    getting_started = " ".join((ROOT / "docs/getting-started.md").read_text().split())
    listed = re.search(r"with every optional extra \(([^)]*)\)", getting_started)
    assert listed and sorted(re.findall(r"`(\w+)`", listed[1])) == sorted(extras)
    assert f'pip install "{torch}" --index-url {CPU_INDEX}' in getting_started
    message = str(MissingExtraError("utamp train", "rl", "torch"))
    assert f"`{message}`" in getting_started  # the error it quotes is the one printed
