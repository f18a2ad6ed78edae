"""Parser tests on the shared typed blocksworld (`tests/blocksworld.py`)."""

from __future__ import annotations

import pytest
from blocksworld import DOMAIN, PROBLEM

from utamp_gym.errors import PddlError
from utamp_gym.symbolic.pddl import (
    Atom,
    Literal,
    check_problem,
    parse_domain,
    parse_plan,
    parse_problem,
)

SAS_PLAN = """\
(pick b s2)
(PLACE b c)

(pick a s1)
(place a b)
; cost = 4 (unit cost)
"""


def test_domain_structure() -> None:
    d = parse_domain(DOMAIN)
    assert d.name == "bw"
    assert d.requirements == (":strips", ":typing", ":negative-preconditions", ":equality")
    assert d.types["block"] == "surface" and d.types["surface"] == "object"
    assert d.types["robot"] == "object"
    assert d.is_subtype("block", "surface") and d.is_subtype("slot", "object")
    assert not d.is_subtype("surface", "block") and not d.is_subtype("robot", "surface")
    assert dict(d.constants) == {"arm": "robot"}
    assert d.predicates["fitson"] == ("block", "surface")
    assert d.predicates["busy"] == ("robot",)
    assert set(d.actions) == {"pick", "place", "regrip"}
    assert d.fluent_predicates() == {"on", "clear", "holding", "busy"}


def test_action_round_trip() -> None:
    pick = parse_domain(DOMAIN).actions["pick"]
    assert pick.parameters == (("?b", "block"), ("?s", "surface"))
    assert [str(lit) for lit in pick.precondition] == [
        "(not (= ?b ?s))",
        "(on ?b ?s)",
        "(clear ?b)",
        "(not (busy arm))",
    ]
    assert pick.add_effects == (
        Atom("holding", ("arm", "?b")),
        Atom("busy", ("arm",)),
        Atom("clear", ("?s",)),
    )
    assert pick.del_effects == (Atom("on", ("?b", "?s")), Atom("clear", ("?b",)))
    pre, add, dele = pick.instantiate(["a", "s1"])
    assert pre[0] == Literal(Atom("=", ("a", "s1")), positive=False)
    assert Atom("holding", ("arm", "a")) in add and Atom("on", ("a", "s1")) in dele


def test_show_keeps_declared_spelling() -> None:
    d = parse_domain(DOMAIN)
    assert d.show(Atom("fitson", ("a", "b"))) == "(fitsOn a b)"
    assert d.show(Literal(Atom("fitson", ("a", "b")), False)) == "(not (fitsOn a b))"


def test_domain_equality_ignores_spelling_and_source() -> None:
    d = parse_domain(DOMAIN, source="bw.pddl")
    assert d.spelling and d.source == "bw.pddl"
    same = d._replace(spelling={}, source="elsewhere.pddl")
    assert same == d and (same != d) is False
    assert d._replace(name="other") != d
    with pytest.raises(TypeError):
        hash(d)  # its mappings are not hashable


def test_problem_round_trip() -> None:
    d = parse_domain(DOMAIN)
    p = parse_problem(PROBLEM, source="bw.pddl", domain=d)
    assert p.name == "bw-3" and p.domain_name == "bw"
    assert dict(p.objects) == {
        "a": "block",
        "b": "block",
        "c": "block",
        "s1": "slot",
        "s2": "slot",
        "s3": "slot",
    }
    assert len(p.init) == 18
    assert Atom("fitson", ("a", "b")) in p.init and Atom("clear", ("a",)) in p.init
    assert [str(lit) for lit in p.goal] == [
        "(on a b)",
        "(on b c)",
        "(clear s1)",
        "(clear s2)",
        "(not (busy arm))",
    ]
    assert parse_problem(PROBLEM) == p  # syntax-only parse gives the same problem


def test_parse_plan_reads_sas_plan() -> None:
    assert parse_plan(SAS_PLAN) == [
        ("pick", "b", "s2"),
        ("place", "b", "c"),
        ("pick", "a", "s1"),
        ("place", "a", "b"),
    ]
    assert parse_plan("; cost = 0 (unit cost)\n\n") == []


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("(domain bw)", "dom.pddl:1: expected exactly one (define (domain NAME) ...)"),
        (DOMAIN.rstrip()[:-1], "dom.pddl:2: unbalanced parentheses: '(' is never closed"),
        (DOMAIN + ")", "dom.pddl:23: unbalanced parentheses: ')'"),
        (
            DOMAIN.replace(
                "(not (busy arm)))\n    :effect (and (holding",
                "(not (bussy arm)))\n    :effect (and (holding",
            ),
            "dom.pddl:12: unknown predicate 'bussy'",
        ),
        (
            DOMAIN.replace("(clear ?b) (not (busy arm))", "(clear ?b ?s) (not (busy arm))"),
            "dom.pddl:12: wrong arity for 'clear'",
        ),
        (
            DOMAIN.replace(
                "(?b - block ?s - surface)\n    :precondition (and (not",
                "(?b - blok ?s - surface)\n    :precondition (and (not",
            ),
            "dom.pddl:11: unknown type 'blok'",
        ),
        (
            DOMAIN.replace("(on ?b ?s) (clear ?b) (not", "(on ?b ?x) (clear ?b) (not"),
            "unknown variable '?x'",
        ),
        (DOMAIN.replace(":equality)", ":equality :adl)"), "unsupported requirement(s) :adl"),
        (
            DOMAIN.replace("(and (holding arm ?b) (clear ?s)", "(or (holding arm ?b) (clear ?s)"),
            "dom.pddl:16: unsupported 'or' in precondition of 'place'",
        ),
    ],
)
def test_domain_errors_name_source_and_problem(text: str, expected: str) -> None:
    with pytest.raises(PddlError) as err:
        parse_domain(text, source="dom.pddl")
    assert expected in str(err.value)


def test_unclosed_parenthesis_reports_opening_line() -> None:
    text = DOMAIN.replace("(clear ?s - surface)", "(clear ?s - surface")
    with pytest.raises(PddlError, match=r"dom\.pddl:7: unbalanced parentheses: '\(' is never"):
        parse_domain(text, source="dom.pddl")


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        ("(clear a)", "(clear z)", "bw.pddl:4: unknown object 'z' in the initial state"),
        ("(clear a)", "(clear a b)", "bw.pddl:4: wrong arity for 'clear'"),
        ("(clear a)", "(clean a)", "bw.pddl:4: unknown predicate 'clean'"),
        ("(on a b) (on b c)", "(on a b) (on b q)", "bw.pddl:8: unknown object 'q' in the goal"),
        ("s3 - slot", "s3 - table", "bw.pddl:3: unknown type 'table' of 's1'"),
        ("(:domain bw)", "(:domain other)", "problem is for domain 'other', not 'bw'"),
    ],
)
def test_problem_errors(old: str, new: str, expected: str) -> None:
    d = parse_domain(DOMAIN)
    with pytest.raises(PddlError) as err:
        parse_problem(PROBLEM.replace(old, new, 1), source="bw.pddl", domain=d)
    assert expected in str(err.value)


def test_check_problem_catches_syntax_only_parse() -> None:
    p = parse_problem(PROBLEM.replace("(clear a)", "(clear z)"), source="bw.pddl")
    with pytest.raises(PddlError, match=r"bw\.pddl: unknown object 'z'"):
        check_problem(parse_domain(DOMAIN), p)


def test_plan_errors_name_line() -> None:
    with pytest.raises(PddlError, match=r"plan:2: expected one '\(action arg \.\.\.\)'"):
        parse_plan("(pick a s1)\npick a s1\n", source="plan")
    with pytest.raises(PddlError, match="plan:1:"):
        parse_plan("(pick (a) s1)\n", source="plan")


@pytest.mark.parametrize("name", ["utamp1", "utamp2"])
def test_packaged_domains_parse(name: str) -> None:
    from utamp_gym.resources import assets_dir

    path = assets_dir() / "pddl" / f"{name}.pddl"
    assert path.is_file(), f"the packaged domain {path} is missing"
    d = parse_domain(path.read_text(), source=str(path))
    assert {"pick-support", "place-support"} <= set(d.actions)
    assert d.show(Atom("canlift", ("a", "b"))) in ("(canLift a b)", "(canlift a b)")


# a blocksworld action whose (static) condition picks what else becomes clear
COND = DOMAIN.replace(
    "(fitsOn ?b - block ?s - surface))",
    "(fitsOn ?b - block ?s - surface) (glued ?b - block ?c - block))",
).replace(
    "(and (not (holding arm ?b)) (holding arm ?b))))",
    "(and (not (holding arm ?b)) (holding arm ?b)\n"
    "      (forall (?c - block) (when (and (glued ?b ?c) (not (= ?c ?b))) (clear ?c)))\n"
    "      (when (glued ?b ?b) (not (busy arm))))))",
)


def test_conditional_effects_resolve_against_static_facts() -> None:
    d = parse_domain(COND)
    regrip = d.actions["regrip"]
    forall, when = regrip.cond_effects
    assert forall.variables == (("?c", "block"),) and when.variables == ()
    assert [str(lit) for lit in forall.condition] == ["(glued ?b ?c)", "(not (= ?c ?b))"]
    assert forall.add == (Atom("clear", ("?c",)),) and when.delete == (Atom("busy", ("arm",)),)
    assert d.condition_predicates() == {"glued"}
    assert "glued" not in d.fluent_predicates()
    facts = {Atom("glued", ("a", "b")), Atom("glued", ("a", "a")), Atom("glued", ("c", "b"))}
    _, add, dele = regrip.instantiate(["a"], facts)
    assert set(add) == {Atom("holding", ("arm", "a")), Atom("clear", ("b",))}
    assert Atom("busy", ("arm",)) in dele
    _, add, dele = regrip.instantiate(["b"], facts)  # b is glued to nothing
    assert add == (Atom("holding", ("arm", "b")),) and dele == (Atom("holding", ("arm", "b")),)
    assert regrip.instantiate(["a"])[1] == (Atom("holding", ("arm", "a")),)  # no facts given


@pytest.mark.parametrize(
    ("effect", "expected"),
    [
        ("(forall (?c - block) (clear ?c))", "unsupported conditional effect in effect of"),
        (
            "(forall (?c - block) (when (not (glued ?b ?c)) (clear ?c)))",
            "forall variable '?c' in effect of 'regrip' must occur in a positive condition",
        ),
        (
            "(forall (?c - block) (when (fitsOn ?b ?c) (clear ?c)))",  # fitsOn ?c: a surface
            "forall variable '?c' in effect of 'regrip' must occur in a positive condition "
            "literal at an argument of type 'block'",
        ),
        (
            "(forall (?c - block) (when (and (glued ?b ?c) (clear ?c)) (busy arm)))",
            "condition (clear ?c) uses the fluent predicate 'clear'",
        ),
        ("(forall (?b - block) (when (glued ?b ?b) (clear ?b)))", "'?b' in effect of 'regrip' is"),
        (
            "(forall (?c - block) (when (glued ?b ?c) (forall (?d - block) (clear ?d))))",
            "unsupported 'forall' in a when in effect of 'regrip'",
        ),
        ("(when (glued ?b ?z) (clear ?b))", "unknown variable '?z'"),
    ],
)
def test_unsupported_conditional_effects_raise(effect: str, expected: str) -> None:
    text = COND.replace(
        "(forall (?c - block) (when (and (glued ?b ?c) (not (= ?c ?b))) (clear ?c)))", effect
    )
    with pytest.raises(PddlError) as err:
        parse_domain(text, source="dom.pddl")
    assert expected in str(err.value) and "dom.pddl:" in str(err.value)


def test_utamp2_slide_brings_every_member_into_the_workspace() -> None:
    from utamp_gym.symbolic.problem import domain_text

    d = parse_domain(domain_text("utamp2"))
    assert ":conditional-effects" in d.requirements
    (member,) = d.actions["slide-support"].cond_effects
    assert member.variables == (("?m", "obj"),)
    assert [str(lit) for lit in member.condition] == ["(ismember ?obj1 ?m)"]
    assert member.add == (Atom("oc", ("in", "workspace", "?m")),)
