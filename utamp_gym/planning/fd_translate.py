"""Fast Downward's own Python translator, run in this process (``solve(translator="fd")``).

Its modules (distribution ``fast-downward.translate``) are imported on first use. It keeps
its options in a module global, so calls are serialised, set the options explicitly and
restore the previous ones, and its progress output is captured.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import math
import threading
from functools import lru_cache
from types import ModuleType

from utamp_gym.errors import PddlError, PlanningError
from utamp_gym.planning.downward import TRANSLATOR_UNSOLVABLE, translator_reason
from utamp_gym.planning.processes import tail

_translate_lock = threading.Lock()  # the translator keeps its options in a module global


@lru_cache(maxsize=1)
def _translator() -> dict[str, ModuleType]:
    """Import the translator modules once (distribution ``fast-downward.translate``)."""
    names = (
        "main",
        "normalize",
        "options",
        "pddl_parser",
        "pddl_parser.lisp_parser",
        "pddl_parser.parsing_functions",
    )
    try:
        return {n: importlib.import_module(f"fast_downward.translate.{n}") for n in names}
    except ImportError as e:
        raise PlanningError(
            "Fast Downward translator not found: install the 'fast-downward.translate' "
            f"distribution (module fast_downward.translate): {e}"
        ) from e


@lru_cache(maxsize=1)
def _default_translate_options() -> argparse.Namespace:
    """The translator's defaults (what the driver uses); the file names are unused."""
    return _translator()["options"].parse_args(["domain.pddl", "problem.pddl"])


def translate(domain: str, problem: str, max_time_s: float) -> tuple[str | None, str | None]:
    """Translate PDDL texts to SAS text in-process.

    Returns ``(sas, None)``, or ``(None, reason)`` if the translator proved the task
    unsolvable. Options are set explicitly on every call and the previous global restored,
    and the translator's progress output is captured, so calls are re-entrant.
    """
    tr = _translator()
    opts = argparse.Namespace(**vars(_default_translate_options()))
    # Invariant synthesis is the only translator step with its own limit (CPU s, int).
    opts.invariant_generation_max_time = max(1, min(300, math.ceil(max_time_s)))
    chatter = io.StringIO()
    with _translate_lock:
        saved = tr["options"].options
        tr["options"].options = opts
        tr["main"].simplified_effect_condition_counter = 0  # statistics globals
        tr["main"].added_implied_precondition_counter = 0
        try:
            with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
                parsed = []
                for label, text in (("domain", domain), ("problem", problem)):
                    try:
                        parsed.append(
                            tr["pddl_parser.lisp_parser"].parse_nested_list(text.splitlines())
                        )
                    except tr["pddl_parser"].ParseError as e:
                        raise tr["pddl_parser"].ParseError(f"{label}: {e}") from e
                task = tr["pddl_parser.parsing_functions"].parse_task(*parsed)
                tr["normalize"].normalize(task)
                sas_task = tr["main"].pddl_to_sas(task)
                out = io.StringIO()
                sas_task.output(out)
        except (tr["pddl_parser"].ParseError, SystemExit, AssertionError, KeyError) as e:
            # SystemExit: the translator exits on unsupported PDDL; never let it end the caller.
            raise PddlError(
                f"Fast Downward translator rejected the PDDL: {e!s}{tail(chatter.getvalue())}"
            ) from e
        except Exception as e:
            raise PlanningError(f"Fast Downward translator failed: {e!r}") from e
        finally:
            tr["options"].options = saved
    unsolvable = TRANSLATOR_UNSOLVABLE.search(chatter.getvalue())
    if unsolvable:
        return None, translator_reason(unsolvable.group(1))
    return out.getvalue(), None


__all__ = ["translate"]
