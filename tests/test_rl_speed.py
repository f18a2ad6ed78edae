"""The fast training path computes what the plain one did, and `utamp train`'s defaults fit
`utamp eval`: the cheaper masked distribution, the slot heads without concatenations, the
encoder's pair bias, the vector env's copies, the env's interface as the default, and grounded
models evaluated wherever their action ids keep their meaning."""

from __future__ import annotations

import csv
import os
import shlex
from pathlib import Path

import numpy as np
import pytest
import torch as th
from sb3_contrib.common.maskable.distributions import MaskableCategorical

from utamp_gym.cli import main
from utamp_gym.env.objects import N_ACTIONS, N_ENTITIES, observation_space
from utamp_gym.rl import slots
from utamp_gym.rl.config import TrainConfig
from utamp_gym.rl.distributions import MaskedCategorical
from utamp_gym.rl.envs import OBJECT_OBS_KEYS, default_interface, make_vec_env
from utamp_gym.rl.harness import shares_actions
from utamp_gym.rl.saved import ModelError, ModelMeta, check_model


def test_masked_categorical_is_sb3_contribs_distribution() -> None:
    gen = th.Generator().manual_seed(0)
    raw = th.randn(16, N_ACTIONS, generator=gen) * 3
    masks = th.rand(16, N_ACTIONS, generator=gen) < 0.02
    masks[:, 5] = True
    actions = masks.float().argmax(-1)  # the first shown action of each row
    grads = []
    for make in (lambda x: MaskableCategorical(logits=x, masks=masks),
                 lambda x: MaskedCategorical(x, masks)):  # fmt: skip
        x = raw.clone().requires_grad_(True)
        d = make(x)
        (d.log_prob(actions).sum() + d.entropy().sum()).backward()
        grads.append((d.probs.detach(), d.log_prob(actions).detach(), d.entropy().detach(),
                      x.grad))  # fmt: skip
    for ours, theirs in zip(grads[1], grads[0], strict=True):
        assert th.allclose(ours, theirs, atol=1e-5, rtol=1e-4)
    assert float(grads[1][0][~masks].max()) == 0.0  # masked actions are never sampled
    d = MaskedCategorical(raw, masks)
    d.apply_masking(None)  # unmasked again: the raw logits' distribution
    assert th.allclose(d.probs, raw.softmax(-1), atol=1e-6)


def _reference_head(head: slots.SlotActionHead, features: th.Tensor) -> th.Tensor:
    """The slot head as concatenations of token features (its first formulation)."""
    k, r, s, d = slots._K, slots._R, slots._S, head.d
    x, g = features[:, : N_ENTITIES * d].reshape(-1, N_ENTITIES, d), features[:, N_ENTITIES * d :]
    b = x.shape[0]
    obj, supports, space = x[:, :k], x[:, : k + r], x[:, k + r :]
    pick = head.pick(th.cat([obj, g[:, None].expand(b, k, d)], -1)).reshape(b, -1)
    oi, sj = obj[:, :, None].expand(b, k, k + r, d), supports[:, None].expand(b, k, k + r, d)
    gp = g[:, None, None].expand(b, k, k + r, d)
    place = head.place(th.cat([oi, sj, oi * sj, gp], -1)).reshape(b, -1)
    oi, sp = obj[:, :, None].expand(b, k, s, d), space[:, None].expand(b, k, s, d)
    slide = head.slide(th.cat([oi, sp, g[:, None, None].expand(b, k, s, d)], -1))
    return th.cat([pick, place, slide.permute(0, 1, 3, 2).reshape(b, -1)], 1)


@pytest.mark.parametrize("d", [64, 32])
def test_the_slot_head_scores_as_its_concatenated_form(d: int) -> None:
    th.manual_seed(0)
    head = slots.SlotActionHead(d)
    features = th.randn(4, (N_ENTITIES + 1) * d)
    assert th.allclose(head(features), _reference_head(head, features), atol=1e-5)


def test_the_encoder_bias_is_the_pair_features_bias() -> None:
    """`_pair_bias` equals each block's bias layer on ``[contact[i, j], contact[j, i]]``, with
    absent keys pushed to -1e9."""
    th.manual_seed(1)
    enc = slots.SlotEncoder(observation_space())
    contact = (th.rand(3, N_ENTITIES, N_ENTITIES, len(slots.PARTS)) < 0.1).float()
    keep = th.rand(3, N_ENTITIES) < 0.6
    got = slots._pair_bias(enc.blocks, contact, keep)
    pairs = th.cat([contact, contact.transpose(1, 2)], -1)
    for i, block in enumerate(enc.blocks):
        want = block.bias(pairs).permute(0, 3, 1, 2)
        part = got[:, i * slots.N_HEADS : (i + 1) * slots.N_HEADS]
        present = keep[:, None, None, :].expand_as(part)  # by key
        assert th.allclose(part[present], want[present], atol=1e-5)
        assert bool((part[~present] < -1e8).all())


def test_vector_env_observations_are_copies_not_the_buffer() -> None:
    vec = make_vec_env("UTampKitchenProcedural-v0", 2, seed=0, obs_keys=OBJECT_OBS_KEYS,
                       masks="geometric", interface="objects")  # fmt: skip
    first = vec.reset()
    kept = {k: v.copy() for k, v in first.items()}
    masks = np.stack(vec.env_method("action_masks"))
    obs, _, _, infos = vec.step(np.array([int(np.flatnonzero(m)[0]) for m in masks]))
    assert all(np.array_equal(first[k], kept[k]) for k in kept)  # not overwritten by step
    assert all(obs[k] is not vec.buf_obs[k] for k in obs)
    info_mask = infos[0]["action_mask"]
    vec.step(np.zeros(2, int))
    assert info_mask is not vec.buf_infos[0]["action_mask"]
    vec.close()


def test_train_takes_its_interface_from_the_env() -> None:
    assert default_interface("UTampKitchenProcedural-v0") == "objects"
    assert default_interface("UTampKitchen-v0") == "grounded"
    assert default_interface("UTampKitchenProcedural-v0", "ppo") == "grounded"
    assert TrainConfig(env_id="UTampKitchenProcedural-v0").interface == "objects"
    assert TrainConfig(env_id="UTampKitchenProcedural-v0", algo="dqn").interface == "grounded"
    assert TrainConfig(env_id="UTampKitchenProcedural-v0", interface="grounded").interface == (
        "grounded"
    )


def _meta(env_id: str, suite: str) -> ModelMeta:
    return ModelMeta(env_id, suite, "maskable-ppo", ("symbolic", "present"), 10, 5,
                     {"masks": "geometric"})  # fmt: skip


def test_grounded_models_are_accepted_where_their_actions_mean_the_same() -> None:
    procedural = _meta("UTampKitchenProcedural-v0", "procedural-v1/train")
    for split in ("train", "test-instances", "test-families", "test-count"):
        assert shares_actions(procedural, f"procedural-v1/{split}")
        check_model(procedural, "m.zip", suite=f"procedural-v1/{split}",
                    same_actions=shares_actions(procedural, f"procedural-v1/{split}"))  # fmt: skip
    kitchen = _meta("UTampKitchen-v0", "pick-place")
    assert not shares_actions(kitchen, "sliding")
    assert not shares_actions(procedural, "pick-place")
    with pytest.raises(ModelError) as err:
        check_model(kitchen, "m.zip", suite="sliding", same_actions=False)
    text = str(err.value)
    assert "\n" not in text and "--interface objects" in text and "evaluate it on" in text


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(f))


@pytest.mark.slow
def test_train_then_eval_on_the_test_families_with_defaults(tmp_path: Path) -> None:
    """The issue's commands: defaults only, the model evaluates on a test split."""
    model = tmp_path / "m"
    assert main(shlex.split(f"train --env UTampKitchenProcedural-v0 --steps 4096 "
                            f"--eval-episodes 4 --no-progress --out {model}")) == 0  # fmt: skip
    out = tmp_path / "eval"
    assert main(shlex.split(
        f"eval --suite procedural-v1/test-families --methods rl:{model}/model.zip "
        f"--grounding symbolic --limit 3 --workers 0 --out {out} --quiet"
    )) == 0  # fmt: skip
    rows = _rows(out / "results.csv")
    assert len(rows) == 3 and all(r["crashed"] == "false" for r in rows)


@pytest.mark.slow
def test_a_grounded_procedural_model_runs_on_another_split(tmp_path: Path) -> None:
    """With ``--interface grounded`` every split shares one action universe: the model is
    accepted on a test split and acts there."""
    model = tmp_path / "m"
    assert main(shlex.split(
        f"train --env UTampKitchenProcedural-v0 --interface grounded --masks geometric "
        f"--steps 64 --envs 2 --eval-every 64 --eval-episodes 2 --no-progress --out {model}"
    )) == 0  # fmt: skip
    out = tmp_path / "eval"
    assert main(shlex.split(
        f"eval --suite procedural-v1/test-count --methods rl:{model}/model.zip "
        f"--grounding symbolic --limit 2 --workers 0 --out {out} --quiet"
    )) == 0  # fmt: skip
    rows = _rows(out / "results.csv")
    assert [r["scene"] for r in rows] == [f"procedural-v1/test-count/{i:04d}" for i in range(2)]
    assert all(r["crashed"] == "false" and int(r["plan_length"]) >= 1 for r in rows)


def test_a_stored_universe_is_the_grounded_one(tmp_path: Path, monkeypatch) -> None:
    """`universe_store`: the universe read back from disk equals the one grounded; an
    unreadable file is ignored; keys naming scene files outside the package are not stored."""
    from utamp_gym.symbolic import universe as universe_mod
    from utamp_gym.symbolic import universe_store
    from utamp_gym.symbolic.universe import UniverseKey

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    key = UniverseKey("utamp2", "gt", "pick-place")
    fresh = universe_mod._ground(key)
    universe_store.save(key, *universe_mod._to_store(fresh))
    path = universe_store.path_of(key)
    assert path is not None and path.is_file() and path.parent == tmp_path / "utamp_gym"
    stored = universe_store.load(key)
    assert stored is not None
    back = universe_mod._from_store(key, *stored)
    for name in ("actions", "fluent_atoms", "static_atoms", "add_bits", "del_bits", "roles",
                 "action_objects"):  # fmt: skip
        assert getattr(back, name) == getattr(fresh, name), name
    for name in ("check_ptr", "check_flat", "static_pre", "static_neg"):
        a, b = getattr(back, name), getattr(fresh, name)
        assert a.dtype == b.dtype and np.array_equal(a, b) and not a.flags.writeable
    assert dict(back.action_index) == dict(fresh.action_index)
    assert back.domain == fresh.domain
    other = UniverseKey("utamp2", "gt", "sliding")
    assert universe_store.path_of(other) != path
    path.write_bytes(b"not an npz")
    assert universe_store.load(key) is None
    assert universe_store.path_of(UniverseKey("utamp2", "gt", None, ("my_scene.json",))) is None
    older = [path.with_name(path.name.rsplit("-", 1)[0] + f"-old{i}.npz") for i in range(5)]
    for i, p in enumerate(older):  # earlier package versions of the same key
        p.write_bytes(b"x")
        os.utime(p, (i, i))
    universe_store.save(key, *universe_mod._to_store(fresh))
    kept = sorted(q.name for q in path.parent.glob(path.name.rsplit("-", 1)[0] + "-*.npz"))
    assert len(kept) == universe_store.KEPT and path.name in kept  # the oldest ones went
    assert universe_store.load(key) is not None
    monkeypatch.setenv("UTAMP_UNIVERSE_CACHE", "0")
    assert universe_store.path_of(key) is None


def _curve(rates: list[float], every: int = 1000) -> list:
    from utamp_gym.rl.callbacks import EvalPoint

    return [EvalPoint((i + 1) * every, 0.0, r, 0.0, 0, "") for i, r in enumerate(rates)]


def test_a_curve_is_flat_only_when_its_last_fifth_gains_little() -> None:
    from utamp_gym.rl.callbacks import plateaued

    rising = [0.05 * i for i in range(12)]
    assert not plateaued(_curve(rising))
    flat = [0.05 * i for i in range(6)] + [0.3] * 10  # steady for the last 10 of 16
    assert plateaued(_curve(flat))
    assert not plateaued(_curve([0.3] * 9))  # too few evaluations to tell
    # one lucky evaluation at the end does not count as a gain: three are averaged
    assert plateaued(_curve([0.3] * 12 + [0.33]))
    assert not plateaued(_curve([0.3] * 12 + [0.4, 0.4, 0.4]))
    assert not plateaued(_curve(flat), min_gain=-1.0)  # nothing gains less than -1


def test_masked_categorical_samples_its_probabilities_and_never_a_masked_action() -> None:
    th.manual_seed(0)
    raw = th.randn(3, 60) * 2
    masks = th.rand(3, 60) < 0.3
    masks[:, 3] = True
    masks[0, 0], masks[1, 59] = False, True  # a masked first action; a shown last one
    d = MaskedCategorical(raw, masks)
    draws = d.sample(th.Size([40_000]))
    assert draws.shape == (40_000, 3) and d.sample().shape == (3,)
    freq = th.stack([th.bincount(draws[:, i], minlength=60).float() / 40_000 for i in range(3)])
    assert bool((freq[~masks] == 0).all())
    assert float((freq - d.probs).abs().max()) < 0.015


def test_the_slot_head_is_saved_with_the_model_and_old_models_keep_theirs(tmp_path: Path) -> None:
    """`utamp train` saves the pointer head's keyword with the model; a model saved without
    one (before the pointer head) loads with the pair head it was trained with."""
    from sb3_contrib import MaskablePPO

    from utamp_gym.rl.config import slot_policy_kwargs

    vec = make_vec_env("UTampKitchenProcedural-v0", 1, seed=0, obs_keys=OBJECT_OBS_KEYS,
                       masks="geometric", interface="objects")  # fmt: skip
    for kwargs, head in (({}, slots.SlotActionHead), (slot_policy_kwargs(), slots.SlotPointerHead)):
        model = MaskablePPO(slots.SlotPolicy, vec, n_steps=16, policy_kwargs=kwargs)
        assert type(model.policy.action_net) is head
        model.save(tmp_path / "m.zip")
        loaded = MaskablePPO.load(tmp_path / "m.zip", device="cpu")
        assert type(loaded.policy.action_net) is head
        obs = vec.reset()
        want = model.policy.state_dict()
        assert all(th.equal(v, loaded.policy.state_dict()[k]) for k, v in want.items())
        action, _ = loaded.predict(obs, action_masks=np.stack(vec.env_method("action_masks")))
        assert vec.env_method("action_masks")[0][int(action[0])]
    with pytest.raises(ValueError, match="unknown slot head 'flat'"):
        MaskablePPO(slots.SlotPolicy, vec, policy_kwargs={"head": "flat"})
    vec.close()
