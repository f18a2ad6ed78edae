"""A minimal client for OpenAI-compatible chat-completions endpoints (standard library only).

Configured by environment variables: ``UTAMP_VLM_BASE_URL`` (e.g.
``https://api.openai.com/v1``), ``UTAMP_VLM_MODEL`` (e.g. ``o4-mini``), ``UTAMP_VLM_API_KEY``
(optional for local servers), and optionally ``UTAMP_VLM_TIMEOUT`` (s, default 180) and
``UTAMP_VLM_REASONING_EFFORT`` (low | medium | high). Every problem (not configured,
HTTP error, time-out, refusal, no JSON in the answer) raises `EndpointError` with a
one-line reason that the evaluation records as the failure.
"""

from __future__ import annotations

import base64
import json
import os
import re
import urllib.error
import urllib.request
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from utamp_gym.errors import EndpointError

ENV_BASE_URL = "UTAMP_VLM_BASE_URL"
ENV_MODEL = "UTAMP_VLM_MODEL"
ENV_API_KEY = "UTAMP_VLM_API_KEY"
ENV_TIMEOUT = "UTAMP_VLM_TIMEOUT"
ENV_EFFORT = "UTAMP_VLM_REASONING_EFFORT"
DEFAULT_TIMEOUT = 180.0
REFUSAL = re.compile(
    r"^\s*(i'?m sorry|i am sorry|sorry,|i can(?:no|')t|i cannot|i am unable|i'?m unable|"
    r"as an ai|i won'?t)",
    re.IGNORECASE,
)
Message = dict[str, Any]


def _short(text: str, n: int = 160) -> str:
    text = " ".join(text.split())
    return text if len(text) <= n else text[: n - 3] + "..."


@dataclass(frozen=True)
class VlmConfig:
    """Where and how to reach the VLM."""

    base_url: str
    model: str
    api_key: str = field(default="", repr=False)
    timeout: float = DEFAULT_TIMEOUT
    reasoning_effort: str | None = None

    @classmethod
    def from_env(cls, env: Mapping[str, str] | None = None) -> VlmConfig:
        """Read the configuration; raises `EndpointError` naming the variables if unset."""
        env = os.environ if env is None else env
        base, model = env.get(ENV_BASE_URL, "").strip(), env.get(ENV_MODEL, "").strip()
        if not base or not model:
            missing = [n for n, v in ((ENV_BASE_URL, base), (ENV_MODEL, model)) if not v]
            raise EndpointError(
                f"no VLM endpoint configured: set {' and '.join(missing)} (and {ENV_API_KEY} "
                f"if the server needs one), e.g. {ENV_BASE_URL}=https://api.openai.com/v1 "
                f"{ENV_MODEL}=o4-mini; any OpenAI-compatible chat-completions server works"
            )
        try:
            timeout = float(env.get(ENV_TIMEOUT) or DEFAULT_TIMEOUT)
        except ValueError:
            raise EndpointError(f"{ENV_TIMEOUT} must be a number of seconds") from None
        effort = env.get(ENV_EFFORT, "").strip() or None
        return cls(base.rstrip("/"), model, env.get(ENV_API_KEY, ""), timeout, effort)


def image_part(png: bytes) -> Message:
    """A user-content part carrying a PNG image as a data URL."""
    url = "data:image/png;base64," + base64.b64encode(png).decode("ascii")
    return {"type": "image_url", "image_url": {"url": url}}


class VlmClient:
    """Sends a conversation and returns the assistant's text."""

    def __init__(self, config: VlmConfig):
        self.config = config

    @classmethod
    def from_env(cls) -> VlmClient:
        return cls(VlmConfig.from_env())

    def chat(self, messages: list[Message]) -> str:
        """The assistant's answer text (refusals and empty answers raise `EndpointError`)."""
        cfg = self.config
        payload: dict[str, Any] = {"model": cfg.model, "messages": messages}
        if cfg.reasoning_effort:
            payload["reasoning_effort"] = cfg.reasoning_effort
        headers = {"Content-Type": "application/json"}
        if cfg.api_key:
            headers["Authorization"] = f"Bearer {cfg.api_key}"
        url = f"{cfg.base_url}/chat/completions"
        request = urllib.request.Request(
            url, data=json.dumps(payload).encode(), headers=headers, method="POST"
        )
        try:
            with urllib.request.urlopen(request, timeout=cfg.timeout) as response:
                body = response.read()
        except urllib.error.HTTPError as exc:
            detail = exc.read().decode(errors="replace") if exc.fp else ""
            raise EndpointError(f"HTTP {exc.code} from {url}: {_short(detail)}") from None
        except TimeoutError:
            raise EndpointError(f"no answer from {url} within {cfg.timeout:g} s") from None
        except urllib.error.URLError as exc:
            if isinstance(exc.reason, TimeoutError):
                raise EndpointError(f"no answer from {url} within {cfg.timeout:g} s") from None
            raise EndpointError(f"cannot reach {url}: {exc.reason}") from None
        except OSError as exc:
            raise EndpointError(f"connection to {url} failed: {exc}") from None
        return answer_text(body)


def answer_text(body: bytes) -> str:
    """The assistant text of a chat-completions response body."""
    try:
        data = json.loads(body)
        choice = data["choices"][0]
        message = choice["message"]
    except (ValueError, KeyError, IndexError, TypeError):
        short = _short(repr(body))
        raise EndpointError(f"malformed response (no choices[0].message): {short}") from None
    if message.get("refusal"):
        raise EndpointError(f"refused: {_short(str(message['refusal']))}")
    if choice.get("finish_reason") == "content_filter":
        raise EndpointError("refused: the answer was withheld by the content filter")
    content = message.get("content")
    if isinstance(content, list):  # some servers return content parts
        content = "".join(p.get("text", "") for p in content if isinstance(p, dict))
    if not isinstance(content, str) or not content.strip():
        raise EndpointError("empty answer")
    return content


def extract_json(text: str) -> dict[str, Any]:
    """The first JSON object in an answer (code fences and surrounding prose allowed)."""
    decoder = json.JSONDecoder()
    for m in re.finditer(r"\{", text):
        try:
            obj, _ = decoder.raw_decode(text, m.start())
        except ValueError:
            continue
        if isinstance(obj, dict):
            return obj
    if REFUSAL.search(text):
        raise EndpointError(f"refused: {_short(text)}")
    raise EndpointError(f"answer is not JSON: {_short(text)}")
