"""vlm-planner with two objects of one kind: the names it must answer with are the ones its
prompt shows (the kind and a number, with where each stands), and its own parser reads
them back to the right objects."""

from __future__ import annotations

import json

from utamp_gym.methods.plan_mapping import answer_names, map_plan
from utamp_gym.methods.planner_prompt import goal_text, naming_note, object_name
from utamp_gym.methods.vlm import run_vlm_planner
from utamp_gym.scene.io import scene_from_dict, scene_to_dict
from utamp_gym.scene.model import Scene
from utamp_gym.suites import resolve_scene


def _two_boards() -> Scene:
    """pick-place/013 (a tray with a pan, a cutting board on slot2) and a second cutting board
    on slot3."""
    data = scene_to_dict(resolve_scene("pick-place/013"))
    data["name"] = "two-boards"
    data["objects"].append(
        {"name": "board2", "type": "cutting-board", "on": "slot3", "orientation": "upright"}
    )
    return scene_from_dict(data)


class _Client:
    """A VLM that detects anything and then answers with `plan`; it keeps what it was sent."""

    def __init__(self, plan: list[str]) -> None:
        self.plan, self.sent = plan, []

    def chat(self, messages: list[dict]) -> str:
        self.sent.append([m["content"] for m in messages])
        return "{}" if len(self.sent) == 1 else json.dumps({"plan": self.plan})


def test_objects_of_one_kind_get_numbers_the_prompt_shows() -> None:
    scene = _two_boards()
    names = answer_names(scene)
    assert names == {"tray": "wooden-tray", "pan": "frying-pan",
                     "board": "cutting-board-1", "board2": "cutting-board-2"}  # fmt: skip
    text = goal_text(scene)
    assert text.endswith(naming_note(scene))
    assert "  - cutting-board-1: the one on the table, in its near-left corner\n" in text
    assert "  - cutting-board-2: the one on the table, in its near-right corner\n" in text
    assert "board2" not in text  # the scene's own names are not in the prompt
    assert object_name(scene, "board2") == "cutting-board-2"
    assert naming_note(resolve_scene("pick-place/013")) == ""  # one of each kind: no note


def test_the_planner_reads_each_numbered_name_back_to_its_object() -> None:
    scene = _two_boards()
    first = map_plan(scene, ["pick cutting-board-1 table"])
    second = map_plan(scene, ["pick Cutting_Board-2 table", "place cutting-board-2 table"])
    assert first.complete and second.complete, (first.error, second.error)
    assert first.actions[0].split()[1] == "board"
    assert [a.split()[1] for a in second.actions] == ["board2", "board2"]
    assert not map_plan(scene, ["pick cutting-board-3 table"]).complete


def test_vlm_planner_sends_the_names_and_maps_its_answer() -> None:
    scene = _two_boards()
    client = _Client(["pick cutting-board-2 table"])
    outcome = run_vlm_planner(scene, client, image=b"png")
    goal_message = client.sent[1][-1]
    assert "cutting-board-2: the one on the table" in goal_message
    assert outcome.solved and outcome.plan[0].startswith("(pick-support board2 ")
