"""A PDDL task whose grounding is long by construction, for tests of time limits.

One action with four parameters whose preconditions are static and hold for every object:
with `n` objects grounding makes n**4 operators (50 objects: 6.25 million, minutes of work
on any machine), while the search, once grounded, would be a single step. A time limit of a
fraction of a second therefore always runs out *during grounding*, however fast or loaded the
machine is.
"""

from __future__ import annotations

DOMAIN = """\
(define (domain wide)
  (:requirements :strips :typing)
  (:types thing)
  (:predicates (ok ?t - thing) (done ?a ?b ?c ?d - thing))
  (:action mark
    :parameters (?a ?b ?c ?d - thing)
    :precondition (and (ok ?a) (ok ?b) (ok ?c) (ok ?d))
    :effect (done ?a ?b ?c ?d)))
"""


def problem(n: int = 50) -> str:
    """`n` things, all ok; the goal marks the first four."""
    things = [f"t{i}" for i in range(n)]
    return (
        f"(define (problem wide-{n}) (:domain wide)\n"
        f"  (:objects {' '.join(things)} - thing)\n"
        f"  (:init {' '.join(f'(ok {t})' for t in things)})\n"
        "  (:goal (done t0 t1 t2 t3)))\n"
    )
