"""Optional extras stay optional: the core imports none of them, and a missing extra is named.

These run with or without the ``dm`` extra (``make test-mujoco4`` runs them without it).
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import textwrap

from procs import user_env


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
