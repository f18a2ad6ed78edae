"""Shared fixtures."""

from __future__ import annotations

import importlib.util
import tomllib
from typing import Any

import pytest

from utamp_gym.resources import asset_path


@pytest.fixture
def demo_dict() -> dict[str, Any]:
    """The demo scene file as plain data (tests mutate their own copy)."""
    return tomllib.loads(asset_path("scenes", "kitchen-demo.toml").read_text())


@pytest.fixture(scope="session")
def session_display():
    """One Xvfb display for windows opened inside the test process (None without Xvfb, or
    without tkinter, which the schematic window needs: a Python built without Tk)."""
    from xvfb import process_display

    if importlib.util.find_spec("tkinter") is None:
        return None
    return process_display()
