"""Which perceived reading made a plan invalid: the false facts an invalid plan used, traced
back to the attribute whose declared value takes each away.

A plan of `utamp2-perceived` is invalid in the declared world when one of its steps needs
an affordance the rules deny on the declared types (`planning.crosscheck.affordance_violations`).
`blame_plan` replays the perceiving and names, for each such false fact, where it came from:

* ``alternative``: the likely readings do not allow it either: only a value the perceiver
  offered as an alternative did (the plan hoped, `utamp_gym.methods.doubt`);
* ``mass``, ``material`` (with the robustness it implies), ``members`` (the boxes of the
  body, handles, edges, necks) or ``parts`` (each side's shape and surface): the likely
  reading of one object the fact names, whose declared value (that attribute alone, the
  rest as perceived) takes the fact away;
* ``geometry``: members and parts together do, neither alone;
* ``combined``: no attribute group of a single object does: the fact needs two readings
  wrong (two objects of a support fact, or two attributes of one).

This is the evaluation layer: it reads the declared scene, which no perceiver sees.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from utamp_gym.affordances.sources import plan_affordances
from utamp_gym.methods.perceived import PerceivedScene, build_perceived_scene
from utamp_gym.planning.crosscheck import affordance_violations
from utamp_gym.scene.catalogue import ObjectType
from utamp_gym.scene.model import Scene
from utamp_gym.symbolic.problem import instantiate_affordances

#: the attribute groups a false fact is traced to, in the order they are tried
SOURCES = ("mass", "material", "members", "parts", "geometry")
#: every origin `blame_plan` reports (a hoped alternative, `SOURCES`, a combination)
ORIGINS = ("alternative", *SOURCES, "combined")


@dataclass(frozen=True)
class FalseFact:
    """One step's false affordance and the readings it came from."""

    step: int  # 0-based
    fact: str  # the atom as the declared problem spells it
    origin: str  # one of `ORIGINS`
    objects: tuple[str, ...] = ()  # the objects whose reading alone takes it away
    #: the declared kind of the member a grasp or lift fact is about (body, handle, edge,
    #: ...); "" for the others
    member: str = ""

    @property
    def predicate(self) -> str:
        return self.fact.strip("()").split()[0]

    def __str__(self) -> str:
        who = f" of {', '.join(self.objects)}" if self.objects else ""
        return f"step {self.step + 1}: {self.fact}: {self.origin}{who}"


def member_kind(scene: Scene, atom: str) -> str:
    """The declared kind of the member `atom` (a grasp, lift or pinch fact:
    ``(pred obj obj-member ...)``) is about; "" if it names none."""
    words = atom.strip("()").split()
    if len(words) < 3 or words[1] not in scene.object_names:
        return ""
    obj = words[1]
    member = words[2][len(obj) + 1 :] if words[2].startswith(obj + "-") else ""
    members = scene.type_of(obj).members
    return members[member].kind if member in members else ""


def with_declared(seen: ObjectType, declared: ObjectType, source: str) -> ObjectType:
    """`seen` with one attribute group (`SOURCES`) at its declared value."""
    if source == "mass":
        return seen._replace(mass=declared.mass)
    if source == "material":
        return seen._replace(material=declared.material, robustness=declared.robustness)
    if source == "members":
        return seen._replace(members=declared.members)
    if source == "parts":
        return seen._replace(parts=declared.parts)
    if source == "geometry":
        return seen._replace(members=declared.members, parts=declared.parts)
    raise ValueError(f"unknown source {source!r}; valid: {', '.join(SOURCES)}")


def _atoms(scene: Scene, ps: PerceivedScene) -> set[str]:
    """The perceived scene's likely facts as atoms of the declared problem."""
    return {a.lower() for a in instantiate_affordances(scene, ps.usable_facts(
        plan_affordances(ps.planning)))}  # fmt: skip


def blame_plan(
    scene: Scene, ps: PerceivedScene, plan: Sequence[str], domain: str = "utamp2"
) -> tuple[FalseFact, ...]:
    """Every false affordance `plan` (planned with the perception `ps` of `scene`) relies on,
    with its origin (module docstring); one entry per distinct fact, at its first step."""
    violations = affordance_violations(scene, plan, domain)
    if not violations:
        return ()
    likely = _atoms(scene, ps)
    out: list[FalseFact] = []
    seen_facts: set[str] = set()
    for step, literal in violations:
        atom = literal.lower()
        if atom in seen_facts:
            continue
        seen_facts.add(atom)
        kind = member_kind(scene, literal)
        if atom not in likely:
            out.append(FalseFact(step, literal, "alternative", member=kind))
            continue
        args = set(literal.strip("()").split()[1:])
        named = [o for o in scene.objects if o.name in args and o.name in ps.types]
        found: list[tuple[str, str]] = []
        for source in SOURCES:
            if found:  # `geometry` only where no single group takes the fact away
                break
            for o in named:
                types = dict(ps.types)
                types[o.name] = with_declared(types[o.name], scene.type_of(o.name), source)
                if atom not in _atoms(scene, build_perceived_scene(scene, types)):
                    found.append((source, o.name))
        if not found:
            out.append(FalseFact(step, literal, "combined", member=kind))
        else:
            objs = tuple(o for _, o in found)
            out.append(FalseFact(step, literal, found[0][0], objs, kind))
    return tuple(out)


__all__ = ["ORIGINS", "SOURCES", "FalseFact", "blame_plan", "member_kind", "with_declared"]
