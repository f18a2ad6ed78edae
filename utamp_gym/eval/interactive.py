"""Interactive perception in the closed loop: look, plan under doubt, revise from what happens.

`InteractivePerception` wraps `utamp2-perceived`'s `PlannerPolicy`. Before the first
decision it looks at the episode's world (the survey; a `Perceiver` of
`utamp_gym.contract.perceiver`) and believes the affordances of the perceived types, with
each attribute the perceiver is unsure of at its cautious value (`utamp_gym.methods.doubt`).
Then the robot's own actions are its measurements:

* **weighing by lifting** – a lift or carry the arm's joint torques refuse (the payload
  model, `utamp_gym.sim.payload`, names the object and the measured load in the failure)
  raises that object's mass belief to the measured load (at least the rated payload when
  the torques saturate), and the rules then withdraw its lifts; a lift that leaves the object
  down ("not liftable by its member") withdraws that member's lift;
* **topples** – a placement after which the object fell off, tipped over on its support or
  toppled the stack marks that support as not supportive for that object (its
  ``isP2PSupportive`` facts are withdrawn);
* **refusals** – an action the world refused because an affordance it needs does not hold
  (the failure names it) withdraws that fact, so no other state plans with it again;
* **extra looks** – when no plan reaches the goal from what is believed, the robot looks
  again (a new survey, perceived afresh: what moved since may have uncovered members and
  rims) and the attributes that block the goal — the doubts planned cautiously — take their
  likely values; the next look hopes: every attribute at the value that promises most, and
  every fact one object's alternative allows (`hoped_facts`: a size reading, a lighter
  mass), for the acts to test; when that leaves the goal unsolvable, the same look also
  hopes for the size readings of two objects at a time (one misreading is likelier than
  two, and a hope the robot acts on may topple a stack: the open loop hopes in the same
  order); only when that still leaves the goal unsolvable does it give up.

After every revision the policy replans from the revised beliefs. `n_weighings` and
`n_looks` count the measurements of the episode (`ClosedLoopResult`, the eval row).
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping
from typing import Any

from utamp_gym.affordances.facts import Fact
from utamp_gym.affordances.sources import plan_affordances
from utamp_gym.agents.planner import PlannerPolicy
from utamp_gym.backend import Surveying
from utamp_gym.contract.perceiver import PerceivedAttributes, Perceiver
from utamp_gym.env.kitchen import UTampKitchenEnv
from utamp_gym.errors import PlanningError
from utamp_gym.methods.doubt import DOUBT_THRESHOLD, Doubt, cautious_types, hoped_facts
from utamp_gym.methods.perceived import (
    PerceivedScene,
    PerceptionError,
    build_perceived_scene,
    perceive_live,
)
from utamp_gym.scene.catalogue import ObjectType

#: extra looks an episode may take when no plan reaches the goal
MAX_LOOKS = 2
#: kg: a load the torques could not hold (saturated) is believed at least this heavy
SATURATED_MASS = 3.5

_PAYLOAD = re.compile(r"^(?P<obj>\S+) exceeds the Panda's .*?(?P<kg>\d+(?:\.\d+)?) kg \(")
_NOT_LIFTABLE = re.compile(r"^(?P<obj>\S+) is not liftable by its (?P<member>[^:]+):")
_TOPPLES = (
    re.compile(r"^(?P<obj>\S+) fell off (?P<support>\S+):"),
    re.compile(r"^(?P<obj>\S+) tipped over on (?P<support>\S+)$"),
    re.compile(r"^placing (?P<obj>\S+) on (?P<support>\S+) toppled the stack"),
)
#: an action the world refused because an affordance it needs does not hold: the env's
#: precondition check in physics, ``(canLift t m)``, or the outcome model in symbolic
#: grounding, ``canLift(t, m) is false``
_REFUSED = (
    re.compile(r"^precondition \((?P<pred>\w+) (?P<args>[^()]*)\) of .* is false \(static\)$"),
    re.compile(r"^(?P<pred>\w+)\((?P<args>[^()]*)\) is false"),
)


class InteractivePerception:
    """``policy(obs, info)``: `utamp2-perceived` acting with interactive perception (module
    docstring). It looks through the env's backend (`Surveying`); in symbolic grounding
    that is the look at the episode's initial world, so reset the env with its world seed
    (``options={"world_seed": s}``)."""

    def __init__(
        self,
        policy: PlannerPolicy,
        env: UTampKitchenEnv,
        *,
        perceiver: Perceiver | None = None,
        doubt: float = DOUBT_THRESHOLD,
        max_looks: int = MAX_LOOKS,
    ) -> None:
        self.policy, self.env = policy, env
        self.perceiver, self.doubt, self.max_looks = perceiver, doubt, max_looks
        self.n_weighings = self.n_looks = 0
        self.seen: PerceivedScene | None = None
        self.beliefs: dict[str, ObjectType] = {}  # object -> believed (perceived) type
        self.doubts: tuple[Doubt, ...] = ()  # planned at their cautious values
        self.untested: set[str] = set()  # objects whose lighter mass is a hypothesis
        #: also believe what some alternative allows (`hoped_facts`): 0 no, 1 one object's,
        #: 2 also two objects' size readings at a time
        self.hoping = 0
        self.weighed: dict[str, float] = {}  # object -> kg it weighs at least (torques)
        self.withdrawn: set[Fact] = set()  # declared-name facts refuted by the robot's acts
        self.revisions: list[str] = []  # what was learnt, in order

    def __call__(self, obs: Any, info: Mapping[str, Any]) -> int:
        if not info.get("action"):  # a new episode: look first
            self.n_weighings = self.n_looks = 0
            self.weighed.clear()
            self.withdrawn.clear()
            self.revisions.clear()
            self._look("first")
        elif info.get("failure_reason"):
            self._revise(str(info["failure_reason"]))
        else:
            self._lifted(str(info["action"]))
        while True:
            try:
                return self.policy(obs, info)
            except PlanningError:
                if not self._look_at_blockers():
                    raise

    # ------------------------------------------------------------------ looking
    def _perceive(self) -> PerceivedScene:
        """A survey through the env's backend (`Surveying`: MuJoCo's cameras, or in symbolic
        grounding the look at the episode's initial world, `SymbolicBackend.survey`)."""
        backend = self.env.backend
        if not isinstance(backend, Surveying):  # (symbolic without a world: NoWorldToLook)
            raise TypeError(
                f"interactive perception looks through the backend's cameras; "
                f"{type(backend).__name__} has none (utamp_gym.backend.Surveying)"
            )
        try:
            return perceive_live(self.env.scene, backend, perceiver=self.perceiver)
        except PerceptionError as exc:  # the episode ends: lost at the perception stage
            raise PlanningError(f"perception: {exc}") from None

    def _look(self, mode: str) -> None:
        """Survey and perceive; the attributes with alternatives at their cautious values
        where in doubt (``first``), at the likely ones (``likely``), or at the values that
        promise most (``hopeful``: hypotheses the robot's acts then test)."""
        seen = self._perceive()
        self.seen, self.untested, self.hoping = seen, set(), int(mode == "hopeful")
        if mode == "likely":
            self.beliefs, self.doubts = dict(seen.types), ()
        else:
            hopeful = mode == "hopeful"
            self.beliefs, doubts = cautious_types(
                seen.planning, seen.types, seen.reports, self.doubt, hopeful=hopeful
            )
            self.doubts = () if hopeful else doubts
            if hopeful:
                self.untested = {d.object for d in doubts if d.attribute == "mass"}
        for obj, kg in self.weighed.items():  # what was weighed stays weighed
            if obj in self.beliefs and kg > self.beliefs[obj].mass:
                self.beliefs[obj] = self.beliefs[obj]._replace(mass=kg)
                self.untested.discard(obj)
        if self.hoping:
            self.untested |= self._lifted_if_lighter()
        self._believe()

    def _lifted_if_lighter(self) -> set[str]:
        """The objects only a lighter mass alternative lets the arm lift (hoped for, so
        their lift weighs them)."""
        assert self.seen is not None
        ps = build_perceived_scene(self.seen.declared, self.beliefs)
        sure = plan_affordances(ps.planning)
        out = set()
        for obj, report in self.seen.reports.items():
            lighter = {"mass": self._hoped(obj, report).alternatives.get("mass", ())}
            if obj not in ps.types or not lighter["mass"]:
                continue
            only = {obj: dataclasses.replace(report, alternatives=lighter)}
            hoped = hoped_facts(ps.planning, ps.types, only) - sure
            if any(f[:2] == ("canLift", ps.types[obj].name) for f in hoped):
                out.add(obj)
        return out

    def _look_at_blockers(self) -> bool:
        """No plan from the beliefs: look again (module docstring); False to give up. The
        first extra look plans the cautious doubts at their likely values (if any); the
        next one tries the values that promise most, to be tested by acting, and hopes for
        one object's misreading before two objects' (no new look for the second)."""
        if self.hoping == 1:
            before = self._facts()
            self.hoping = 2
            after = before | self._facts(singles=False)  # one object's hopes: computed above
            if after != before:  # (no two objects offer size readings: nothing more to hope)
                self.revisions.append("no plan: hoping for two objects' size readings too")
                self._believe(after)
                return True
        if self.n_looks >= self.max_looks:
            return False
        self.n_looks += 1
        mode = "likely" if self.doubts else "hopeful"
        blockers = ", ".join(f"{d.object}.{d.attribute}" for d in self.doubts) or "none in doubt"
        self.revisions.append(f"look {self.n_looks} ({mode}): no plan; doubts: {blockers}")
        self._look(mode)
        return True

    def _lifted(self, action: str) -> None:
        """A successful action: a pick of an object whose mass was a hypothesis weighed it."""
        words = action.strip("()").split()
        if len(words) > 1 and words[0].startswith("pick") and words[1] in self.untested:
            self.untested.discard(words[1])
            self.n_weighings += 1
            self.revisions.append(f"weighed {words[1]}: the arm lifts it")

    # ------------------------------------------------------------------ revising
    def _revise(self, reason: str) -> None:
        """Revise the beliefs from a failed action's reason (module docstring)."""
        scene = self.env.scene
        m = _PAYLOAD.match(reason)
        if m and m["obj"] in self.beliefs:
            kg = float(m["kg"])
            kg = max(kg, SATURATED_MASS) if "cannot hold" in reason else kg
            self.weighed[m["obj"]] = max(kg, self.weighed.get(m["obj"], 0.0))
            self.untested.discard(m["obj"])
            t = self.beliefs[m["obj"]]
            self.beliefs[m["obj"]] = t._replace(mass=max(t.mass, kg))
            self.n_weighings += 1
            self.revisions.append(f"weighed {m['obj']}: at least {kg:.2f} kg")
            self._believe()
            return
        m = _NOT_LIFTABLE.match(reason)
        if m and m["obj"] in self.beliefs:
            self.n_weighings += 1
            self.untested.discard(m["obj"])
            self.withdrawn.add(("canLift", scene.object(m["obj"]).type, m["member"].strip()))
            self.revisions.append(f"lifted {m['obj']} by its {m['member']}: it stayed down")
            self._believe()
            return
        for pattern in _TOPPLES:
            m = pattern.match(reason)
            if m and m["obj"] in self.beliefs and m["support"] in scene.object_names:
                under, over = scene.object(m["support"]).type, scene.object(m["obj"]).type
                facts = self._facts()
                self.withdrawn.update(
                    f for f in facts if f[0] == "isP2PSupportive" and f[2:5:2] == (under, over)
                )
                self.revisions.append(f"{m['obj']} does not stand on {m['support']}")
                self._believe(facts)
                return
        for pattern in _REFUSED:
            m = pattern.match(reason)
            if m:
                args = tuple(a.strip() for a in m["args"].replace(",", " ").split())
                fact, facts = (m["pred"], *args), self._facts()
                if fact in facts and fact not in self.withdrawn:
                    self.withdrawn.add(fact)
                    self.revisions.append(f"refused: {fact[0]}({', '.join(args)}) withdrawn")
                    self._believe(facts)
                return

    def _facts(self, *, singles: bool = True) -> frozenset[Fact]:
        """The facts believed: the believed types' and, hoping, those some alternative the
        perceiver offers for the objects they concern allows (`hoped_facts`; a mass below
        what the arm weighed is no longer one), in the declared names. Without `singles`,
        of the hoped facts only those two objects' size readings add (`hoped_facts`)."""
        assert self.seen is not None
        ps = build_perceived_scene(self.seen.declared, self.beliefs)
        facts = plan_affordances(ps.planning)
        if self.hoping:
            reports = {obj: self._hoped(obj, r) for obj, r in self.seen.reports.items()}
            facts |= hoped_facts(
                ps.planning, ps.types, reports, singles=singles, pairs=self.hoping > 1
            )
        return ps.usable_facts(facts)

    def _hoped(self, obj: str, report: PerceivedAttributes) -> PerceivedAttributes:
        """`report` without the mass alternatives lighter than what the arm weighed."""
        if obj not in self.weighed:
            return report
        masses = tuple(
            v for v in report.alternatives.get("mass", ()) if _kg(v) >= self.weighed[obj]
        )
        return dataclasses.replace(report, alternatives={**report.alternatives, "mass": masses})

    def _believe(self, facts: frozenset[Fact] | None = None) -> None:
        """Plan from the believed facts (`facts`: `_facts()` if already computed for the
        current beliefs) less those the acts refuted."""
        facts = self._facts() if facts is None else facts
        self.policy.believe(self.env.scene.name, facts - self.withdrawn)


def _kg(value: Any) -> float:
    """A mass alternative in kg (inf if it is not a number: not lighter than anything)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.inf


__all__ = ["MAX_LOOKS", "InteractivePerception"]
