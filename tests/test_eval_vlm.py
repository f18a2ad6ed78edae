"""VLM methods against a local OpenAI-compatible server replaying recorded answers.

The server (http.server on 127.0.0.1, random port, in a thread) answers each POST to
/v1/chat/completions with the next scripted reply: good answers, prose, refusals,
missing fields, unknown objects, HTTP errors and a reply slower than the client's
time-out. Every bad answer must become a failure row with a reason, never a crash.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest

from utamp_gym.cli import main
from utamp_gym.errors import EndpointError
from utamp_gym.eval.runner import EvalTask, run_task
from utamp_gym.eval.sweep import SweepConfig, run_sweep
from utamp_gym.methods.vlm import prompt
from utamp_gym.methods.vlm_client import VlmConfig
from utamp_gym.scene.geometry import SIDES
from utamp_gym.suites import get_scene

SCENE = "pick-place/013"  # tray/pan | board
ENV = ("UTAMP_VLM_BASE_URL", "UTAMP_VLM_MODEL", "UTAMP_VLM_API_KEY")


def completion(content: str | None, *, refusal: str | None = None, finish: str = "stop") -> dict:
    message = {"role": "assistant", "content": content, "refusal": refusal}
    return {
        "id": "chatcmpl-test",
        "object": "chat.completion",
        "model": "test-vlm",
        "choices": [{"index": 0, "message": message, "finish_reason": finish}],
    }


def attributes(scene_name: str = SCENE, **changes: Any) -> dict:
    """The true attributes of the scene's objects, as a perfect VLM would report them."""
    scene = get_scene(scene_name)
    objects = []
    for name in dict.fromkeys(o.type for o in scene.objects):
        t = scene.catalogue[name]
        parts = {
            s: {"shape": t.parts[s].shape, "food_surface": t.parts[s].food_surface} for s in SIDES
        }
        entry = {"name": name, "material": t.material, "mass_kg": t.mass}
        objects.append({**entry, "robustness": t.robustness, "parts": parts})
    data = {"objects": objects}
    for key, value in changes.items():
        data[key] = value
    return data


def fenced(data: dict) -> str:
    return "Here is what I see.\n```json\n" + json.dumps(data) + "\n```"


class Server:
    """Scripted replies: (HTTP status, JSON body or raw bytes, delay in s)."""

    def __init__(self) -> None:
        self.replies: list[tuple[int, Any, float]] = []
        self.requests: list[dict] = []
        server = self

        class Handler(BaseHTTPRequestHandler):
            def do_POST(self) -> None:
                body = self.rfile.read(int(self.headers["Content-Length"]))
                server.requests.append({"path": self.path, **json.loads(body)})
                status, reply, delay = server.replies.pop(0) if server.replies else (500, {}, 0)
                time.sleep(delay)
                data = reply if isinstance(reply, bytes) else json.dumps(reply).encode()
                try:
                    self.send_response(status)
                    self.send_header("Content-Type", "application/json")
                    self.send_header("Content-Length", str(len(data)))
                    self.end_headers()
                    self.wfile.write(data)
                except OSError:
                    pass  # the client gave up (time-out test)

            def log_message(self, *args: Any) -> None:
                pass

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}/v1"

    def reply(self, body: Any, status: int = 200, delay: float = 0.0) -> None:
        self.replies.append((status, body, delay))


@pytest.fixture
def vlm(monkeypatch: pytest.MonkeyPatch) -> Iterator[Server]:
    server = Server()
    thread = threading.Thread(target=server.httpd.serve_forever, daemon=True)
    thread.start()
    monkeypatch.setenv("UTAMP_VLM_BASE_URL", server.url)
    monkeypatch.setenv("UTAMP_VLM_MODEL", "test-vlm")
    monkeypatch.setenv("UTAMP_VLM_API_KEY", "sk-test")
    monkeypatch.setenv("UTAMP_VLM_TIMEOUT", "5")  # replies come at once; a loaded machine is slow
    yield server
    server.httpd.shutdown()
    server.httpd.server_close()


def _run(method: str) -> Any:
    return run_task(EvalTask(SCENE, method, grounding="symbolic"))


def test_utamp2_vlm_with_perfect_attributes(vlm: Server) -> None:
    vlm.reply(completion(fenced(attributes())))
    row = _run("utamp2-vlm")
    assert row.success and row.solved and not row.crashed, row.failure_reason
    assert row.affordance_f1 == 1.0 and row.planning_time_s is not None
    req = vlm.requests[0]
    assert req["path"] == "/v1/chat/completions" and req["model"] == "test-vlm"
    system, user = req["messages"]
    assert "salt-shaker" in system["content"] and "concave" in system["content"]
    image = user["content"][1]["image_url"]["url"]
    assert image.startswith("data:image/png;base64,") and len(image) > 1000


def test_wrong_attributes_fail_with_an_explanation(vlm: Server) -> None:
    data = attributes()
    pan = next(o for o in data["objects"] if o["name"] == "frying-pan")
    pan["parts"]["on"]["shape"] = "round"  # the pan can no longer carry the board
    vlm.reply(completion(json.dumps(data)))
    row = _run("utamp2-vlm")
    assert not row.solved and not row.crashed and row.affordance_f1 < 1.0
    assert "missing affordance facts" in row.failure_reason
    assert "isP2PSupportive(on, frying-pan, under, cutting-board)" in row.failure_reason


BAD_REPLIES = {
    "prose": (200, completion("A tray, a pan and a board on a table."), 0, "not JSON"),
    "refusal-field": (200, completion(None, refusal="I can't help with that."), 0, "refused"),
    "refusal-text": (200, completion("I'm sorry, but I can't assist with that."), 0, "refused"),
    "filtered": (200, completion("", finish="content_filter"), 0, "refused"),
    "empty": (200, completion("   "), 0, "empty answer"),
    "no-choices": (200, {"error": "overloaded"}, 0, "malformed response"),
    "not-json-body": (200, b"<html>gateway</html>", 0, "malformed response"),
    "http-500": (500, {"error": {"message": "internal"}}, 0, "HTTP 500"),
    "http-401": (401, {"error": {"message": "bad key"}}, 0, "HTTP 401"),
    "timeout": (200, completion("{}"), 7.0, "within 5 s"),
    "no-objects": (200, completion('{"things": []}'), 0, "has no 'objects'"),
    "unknown-object": (200, None, 0, "unknown object 'spoon'"),
    "missing-parts": (200, None, 0, "has no 'parts'"),
    "bad-shape": (200, None, 0, "shape 'wobbly'"),
    "missed-object": (200, None, 0, "answer misses objects"),
}


def _bad_attributes(case: str) -> dict:
    data = attributes()
    if case == "unknown-object":
        data["objects"].append({**data["objects"][0], "name": "spoon"})
    elif case == "missing-parts":
        del data["objects"][0]["parts"]
    elif case == "bad-shape":
        data["objects"][0]["parts"]["on"]["shape"] = "wobbly"
    elif case == "missed-object":
        data["objects"].pop()
    return completion(json.dumps(data))


@pytest.mark.parametrize("case", sorted(BAD_REPLIES))
def test_malformed_answers_become_failure_rows(vlm: Server, case: str) -> None:
    status, body, delay, expected = BAD_REPLIES[case]
    vlm.reply(_bad_attributes(case) if body is None else body, status, delay)
    row = _run("utamp2-vlm")
    assert not row.success and not row.solved and not row.crashed
    assert row.failure_reason.startswith("not solved: VLM: ")
    assert expected in row.failure_reason, row.failure_reason


def test_vlm_planner_valid_plan(vlm: Server) -> None:
    vlm.reply(completion(fenced(attributes())))
    plan = ["pick cutting-board table", "place cutting-board frying-pan"]
    vlm.reply(completion(json.dumps({"plan": plan})))
    row = _run("vlm-planner")
    assert row.success and row.plan_length == 2, row.failure_reason
    assert row.plan.startswith("(pick-support board board-handle")
    second = vlm.requests[1]["messages"]
    assert [m["role"] for m in second] == ["system", "user", "assistant", "user"]
    assert "wooden-tray" in second[-1]["content"] and "pick" in second[0]["content"]


@pytest.mark.parametrize(
    ("plan", "expected"),
    [
        (["pick frying-pan tray", "place frying-pan cutting-board"], "isP2PSupportive"),
        (["pick cutting-board table", "pick frying-pan tray"], "(oc in hand air) is false"),
        (["pick spoon table"], "unknown object 'spoon'"),
        (["fly cutting-board moon"], "expected 'pick|place"),
        (["pick cutting-board table"], "goal literal"),
    ],
)
def test_vlm_planner_invalid_plans_fail(vlm: Server, plan: list[str], expected: str) -> None:
    vlm.reply(completion(json.dumps(attributes())))
    vlm.reply(completion(json.dumps({"plan": plan})))
    row = _run("vlm-planner")
    assert not row.success and not row.crashed
    assert expected in row.failure_reason, row.failure_reason


def test_vlm_planner_refusal_and_missing_plan(vlm: Server) -> None:
    vlm.reply(completion(json.dumps(attributes())))
    vlm.reply(completion(None, refusal="I cannot plan for robots."))
    assert "refused" in _run("vlm-planner").failure_reason
    vlm.reply(completion(json.dumps(attributes())))
    vlm.reply(completion('{"steps": ["pick a b"]}'))
    assert "has no 'plan'" in _run("vlm-planner").failure_reason


def test_no_endpoint_fails_fast(monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys) -> None:
    for name in ENV:
        monkeypatch.delenv(name, raising=False)
    with pytest.raises(EndpointError) as err:
        VlmConfig.from_env()
    assert all(name in str(err.value) for name in ENV)
    with pytest.raises(EndpointError):
        run_sweep(SweepConfig("pick-place", ("utamp2-vlm",), limit=1), tmp_path, progress=False)
    args = ["eval", "--suite", "pick-place", "--methods", "vlm-planner", "--out", str(tmp_path)]
    assert main(args) == 2
    assert "UTAMP_VLM_BASE_URL" in capsys.readouterr().err


def test_prompts_are_packaged() -> None:
    text = prompt("planner_goal", base="wooden-tray", workspace_note="", space_note="")
    assert "wooden-tray" in text and "$" not in text
    for name in ("attributes_request", "planner_system"):
        assert prompt(name).strip()
