"""The before/after picture page of the goal templates (`benchmarks/template_pictures.py`):
one deterministic scene per template, small PNGs with their provenance, captions that are the
current code's instruction and goal literals."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

from utamp_gym import provenance
from utamp_gym.suites import resolve_scene
from utamp_gym.suites.procedural_v2 import split_scenes
from utamp_gym.suites.procedural_v2.spec import SPLITS
from utamp_gym.tasks.language import instruction

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_scripts"))

import readme  # noqa: E402

pictures = readme.load_script("benchmarks/template_pictures.py")
PAGE = ROOT / "docs" / "results" / "template_pictures.md"
IMAGES = ROOT / "docs" / "results" / "template_pictures"


def test_every_template_of_v2_has_a_candidate_in_a_fixed_order() -> None:
    templates = {s.template for split in SPLITS for s in split_scenes(split)}
    assert set(pictures.TEMPLATE_ORDER) == templates and len(templates) == 13
    for t in pictures.TEMPLATE_ORDER:
        first = pictures.candidates(t)
        assert first and all(s.achievable and s.template == t for s in first)
        assert [s.scene.name for s in pictures.candidates(t)] == [s.scene.name for s in first]
    # test splits first: hard only for the template that lives there alone
    assert pictures.candidates("restack")[0].scene.name.startswith("procedural-v2/hard/")
    assert pictures.candidates("tower")[0].scene.name.split("/")[1].startswith("test-")


def test_the_page_shows_each_template_with_the_codes_own_captions() -> None:
    text = PAGE.read_text()
    prov = provenance.parse_footer(text)
    assert prov is not None and "benchmarks/template_pictures.py" in prov["command"]
    sections = re.findall(r"^### (\S+)\n\n`(procedural-v2/[\w-]+/\d{4})`[^:]*: \*\"(.*)\"\*$",
                          text, flags=re.M)  # fmt: skip
    assert [t for t, _, _ in sections] == list(pictures.TEMPLATE_ORDER)
    for template, name, said in sections:
        scene = resolve_scene(name)
        assert scene.goal is not None and scene.goal.template == template
        assert said == instruction(scene, scene.goal)
        for lit in scene.goal.literals:
            assert f"`{lit}`" in text
    assert "no VLM" not in text  # (the planning page says that; this one runs physics)
    assert re.search(r"Physics succeeded on \d+ of 13", text)


@pytest.mark.parametrize("when", ["before", "after"])
def test_pictures_are_small_stamped_pngs(when: str) -> None:
    from PIL import Image

    for t in pictures.TEMPLATE_ORDER:
        path = IMAGES / f"{t}-{when}.png"
        assert path.stat().st_size <= pictures.MAX_BYTES, path
        with Image.open(path) as image:
            assert image.size == (320, 240)
        prov = provenance.read_png(path)
        assert prov is not None and "template_pictures.py" in prov["command"]


@pytest.mark.slow
@pytest.mark.physics
def test_a_picture_shows_the_state_before_and_after_a_successful_run() -> None:
    s = pictures.candidates("put-on")[0]
    run = pictures.picture(s.scene, 0, (160, 120))
    assert run["execution"].success
    before, after = run["before"], run["after"]
    assert before.shape == after.shape == (120, 160, 3)
    assert np.abs(before.astype(int) - after.astype(int)).mean() > 1.0  # the world changed
    png = pictures._png(before, {"commit": "abc1234", "command": "python x.py"})
    assert len(png) < pictures.MAX_BYTES and png.startswith(b"\x89PNG")
