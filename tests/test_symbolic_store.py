"""The planner's disk store (`utamp_gym.symbolic.store`): a parsed domain and its join orders
come back equal to freshly computed ones; a damaged, foreign or switched-off store is
ignored and the work is redone."""

from __future__ import annotations

import marshal

import pytest

from utamp_gym.symbolic import join_store, store
from utamp_gym.symbolic.joins import join_plan
from utamp_gym.symbolic.pddl import cached_domain, parse_domain
from utamp_gym.symbolic.problem import domain_text
from utamp_gym.symbolic.reach import Grounder


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("UTAMP_PLAN_CACHE", raising=False)
    cached_domain.cache_clear()
    join_store._known.clear()
    yield tmp_path / "utamp_gym"
    cached_domain.cache_clear()
    join_store._known.clear()


def _plans(grounder: Grounder) -> list[object]:
    """The grounder's join orders, itemgetters as their repr (they compare by identity)."""
    out = []
    for plan in (*[p for g in grounder._group_plans for p in g],
                 *[p for m in grounder._main_plans for p in m.values()]):  # fmt: skip
        steps, late, unbound = plan
        out.append(([(*s[:5], repr(s.getter), *s[6:]) for s in steps], late, unbound))
    return out


@pytest.mark.parametrize("name", ["utamp2", "utamp1"])
def test_stored_domain_and_join_orders_equal_fresh_ones(cache, name: str) -> None:
    text = domain_text(name)
    first = cached_domain(text, f"{name}.pddl")
    made = _plans(Grounder(first))
    assert {p.name.split("-")[0] for p in cache.iterdir()} == {"domain", "joins"}
    cached_domain.cache_clear()
    join_store._known.clear()
    again = cached_domain(text, f"{name}.pddl")  # read back from the files
    assert again is not first and again == parse_domain(text, f"{name}.pddl")
    assert again.spelling == first.spelling and again.source == first.source
    assert _plans(Grounder(again)) == made
    fresh = Grounder(parse_domain(text))
    for g, schema in enumerate(fresh._schemas):
        assert fresh._main_plans[g][None][2] == join_plan(schema.main, None)[2]


def test_damaged_or_foreign_files_are_ignored(cache) -> None:
    text = domain_text("utamp2")
    good = cached_domain(text, "utamp2.pddl")
    Grounder(good)
    files = sorted(cache.iterdir())
    for path in files:
        if path.name.startswith("domain"):
            path.write_bytes(b"\x00garbage")
        else:
            key, data = marshal.loads(path.read_bytes())
            path.write_bytes(marshal.dumps((key, (("not", "a plan"),) * len(data))))
    cached_domain.cache_clear()
    join_store._known.clear()
    assert cached_domain(text, "utamp2.pddl") == good
    assert _plans(Grounder(good)) == _plans(Grounder(parse_domain(text)))
    key = store.key_of("other input")
    store.save("domain", key, store.encode_domain(good))
    assert store.load("domain", store.key_of("yet another")) is None
    assert store.decode_domain(store.load("domain", key)) == good


def test_the_store_can_be_switched_off(cache, monkeypatch) -> None:
    monkeypatch.setenv("UTAMP_PLAN_CACHE", "0")
    Grounder(cached_domain(domain_text("utamp2"), "utamp2.pddl"))
    assert not cache.exists()
    assert store.path_of("joins", "k") is None
