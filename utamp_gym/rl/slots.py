"""An object-centric policy for the objects interface: a relational transformer over slots.

Why: an agent that must act on objects it has not seen, in numbers it has not seen, needs a
network that treats every object slot alike. `SlotEncoder` (an SB3 features extractor) turns
each object, table region and free space into a token from its own attributes, pose and
relations, and runs `N_LAYERS` of self-attention whose scores get a learned bias from the
pair's contact relations (``contact[i, j]`` and ``contact[j, i]``), with absent slots masked
out. `SlotActionHead` scores every index of the objects interface from the tokens it names:
a pick from the object's token, a place from the (object, support) pair, a slide from the
(object, space) pair; the value comes from the mean of the present tokens. So the network is
equivariant to slot order and its size does not depend on the scene, nor on the slot count
(read from the observation space: 6, or 8 for procedural-v2's test-count).

**Goals.** On an env with the goal in its observation (``UTampKitchenGoals-v0``) the encoder is
goal-conditioned (`SlotEncoder`): per slot the goal's parts, per pair its relations in the
attention bias and as a direct term of each (object, support) place logit. A model saved
without goal entries builds the same modules as before and acts identically.

`SlotPolicy` is MaskablePPO's policy with this extractor and these heads (SB3 saves it by
reference, so `MaskablePPO.load` finds it wherever `utamp_gym` is installed); behaviour
cloning (`utamp_gym.rl.bc`) trains the same class.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch as th
from gymnasium import spaces
from sb3_contrib.common.maskable.policies import MaskableMultiInputActorCriticPolicy
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

from utamp_gym.env.object_goal import GOAL_KEYS
from utamp_gym.env.objects import (
    GRASPS,
    MAX_MEMBERS,
    MAX_OBJECTS,
    MAX_REGIONS,
    MAX_SPACES,
    N_ATTRIBUTES,
    n_actions,
    n_entities,
    slot_count,
)
from utamp_gym.rl.distributions import use_fast_masked
from utamp_gym.rl.policies import _TrainedKeys
from utamp_gym.scene.geometry import PARTS, SIDES

D_MODEL = 64  # the width of a slot policy saved without ``features_extractor_kwargs``
N_HEADS = 4
N_LAYERS = 2
_K, _R, _S, _M, _G = MAX_OBJECTS, MAX_REGIONS, MAX_SPACES, MAX_MEMBERS, len(GRASPS)
_P = len(PARTS)
#: per object: attributes, pose, up side, held, free parts, in workspace, members there, grasp
OBJECT_WIDTH = N_ATTRIBUTES + 7 + len(SIDES) + 1 + _P + 1 + _M + _M * _G
PLACE_WIDTH = 5 + _P + 1  # regions and spaces: geometry, free parts, in workspace


class _Block(nn.Module):
    """Pre-norm self-attention with a per-head bias from pair features, then an MLP."""

    def __init__(self, d: int, heads: int, pair_width: int) -> None:
        super().__init__()
        self.heads, self.dh = heads, d // heads
        self.norm1, self.norm2 = nn.LayerNorm(d), nn.LayerNorm(d)
        self.qkv, self.out = nn.Linear(d, 3 * d), nn.Linear(d, d)
        self.bias = nn.Linear(pair_width, heads)
        self.mlp = nn.Sequential(nn.Linear(d, 2 * d), nn.ReLU(), nn.Linear(2 * d, d))

    def forward(self, x: th.Tensor, bias: th.Tensor) -> th.Tensor:
        """`bias` (b, heads, n, n): this block's pair bias, absent keys at −1e9 (`_pair_bias`)."""
        b, n, d = x.shape
        qkv = self.qkv(self.norm1(x)).view(b, n, 3, self.heads, self.dh).permute(2, 0, 3, 1, 4)
        q, k, v = qkv.unbind(0)  # (b, heads, n, dh)
        scores = (q @ k.transpose(-1, -2)) / math.sqrt(self.dh) + bias
        att = (scores.softmax(-1) @ v).transpose(1, 2).reshape(b, n, d)
        x = x + self.out(att)
        return x + self.mlp(self.norm2(x))


def _pair_bias(blocks: nn.ModuleList, contact: th.Tensor, keep: th.Tensor) -> th.Tensor:
    """Every block's attention bias at once: ``block.bias`` of the pair features
    ``[contact[i, j], contact[j, i]]``, computed from `contact` without building the pairs
    (the two halves of the weight apply to `contact` and to its transpose), with the keys of
    absent entities at −1e9. Returns (b, blocks · heads, n, n)."""
    weight = th.cat([blk.bias.weight for blk in blocks])  # (blocks · heads, 2 · parts)
    offset = th.cat([blk.bias.bias for blk in blocks])
    p = contact.shape[-1]
    direct = contact @ weight[:, :p].T  # (b, i, j, blocks · heads)
    reverse = contact @ weight[:, p:].T
    bias = direct + reverse.transpose(1, 2) + offset
    absent = (~keep)[:, None, None, :] * -1e9
    return bias.permute(0, 3, 1, 2) + absent


def has_goal(observation_space: spaces.Dict) -> bool:
    """Whether an objects-interface observation space has the goal entries
    (`utamp_gym.env.object_goal.GOAL_KEYS`)."""
    return all(k in observation_space.spaces for k in GOAL_KEYS)


class SlotEncoder(BaseFeaturesExtractor):
    """Tokens of the objects interface's observation, encoded (module docstring).

    Features: the E tokens (objects, regions, spaces; E = `n_entities` of the space's slot
    count) of width `d_model`, flat, followed by the mean of the present tokens. With the
    goal entries in the observation space (`has_goal`) the encoder is goal-conditioned: each
    entity's token adds its goal parts (``goal_free``, ``goal_not_free``), each block's
    attention bias adds the pair's goal relations (``goal_contact`` and ``goal_not_contact``,
    both directions), and the features end with a goal score per (object, support) pair
    that the heads add to the place logits. Without them (every model saved before) the
    modules, parameters and outputs are those of the goal-free encoder.
    """

    def __init__(
        self, observation_space: spaces.Dict, d_model: int = D_MODEL, n_layers: int = N_LAYERS
    ) -> None:
        k, goal = slot_count(observation_space), has_goal(observation_space)
        width = (n_entities(k) + 1) * d_model + (k * (k + _R) if goal else 0)
        super().__init__(observation_space, features_dim=width)
        self.d_model, self.k, self.goal = d_model, k, goal
        self.objects = nn.Sequential(nn.Linear(OBJECT_WIDTH, d_model), nn.ReLU())
        self.places = nn.Sequential(nn.Linear(PLACE_WIDTH, d_model), nn.ReLU())
        self.kind = nn.Parameter(th.zeros(3, d_model))  # object, region, space
        self.blocks = nn.ModuleList(_Block(d_model, N_HEADS, 2 * _P) for _ in range(n_layers))
        self.norm = nn.LayerNorm(d_model)
        if goal:  # added only then: a goal-free model's state dict is unchanged
            self.goal_token = nn.Linear(2 * _P, d_model)
            self.goal_bias = nn.ModuleList(nn.Linear(4 * _P, N_HEADS) for _ in range(n_layers))
            self.goal_place = nn.Linear(2 * _P, 1)

    def forward(self, obs: dict[str, th.Tensor]) -> th.Tensor:
        b, k = obs["present"].shape[0], self.k
        free, ws = obs["free"], obs["in_workspace"][..., None]
        objects = th.cat([
            obs["attributes"], obs["poses"], obs["up"], obs["held"][..., None], free[:, :k],
            ws[:, :k], obs["member_in_workspace"], obs["grasp"].reshape(b, k, -1),
        ], -1)  # fmt: skip
        places = th.cat([th.cat([obs["regions"], obs["spaces"]], 1), free[:, k:], ws[:, k:]], -1)
        x = th.cat([self.objects(objects), self.places(places)], 1)
        kind = th.cat([self.kind[0].expand(k, -1), self.kind[1].expand(_R, -1),
                       self.kind[2].expand(_S, -1)])  # fmt: skip
        x = x + kind
        keep = th.cat([obs["present"], obs["regions"][..., 0], obs["spaces"][..., 0]], 1) > 0.5
        bias = _pair_bias(self.blocks, obs["contact"], keep)
        if self.goal:
            x = x + self.goal_token(th.cat([obs["goal_free"], obs["goal_not_free"]], -1))
            bias = bias + _goal_bias(self.goal_bias, obs["goal_contact"], obs["goal_not_contact"])
        for block, block_bias in zip(self.blocks, bias.split(N_HEADS, 1), strict=True):
            x = block(x, block_bias)
        x = self.norm(x) * keep[..., None]
        pooled = x.sum(1) / keep.sum(1, keepdim=True).clamp(min=1)
        out = [x.reshape(b, -1), pooled]
        if self.goal:  # per (object i, support j): the goal's say on placing i on j
            pair = th.cat([obs["goal_contact"], obs["goal_not_contact"]], -1)[:, :k, : k + _R]
            out.append(self.goal_place(pair).reshape(b, -1))
        return th.cat(out, 1)


def _goal_bias(layers: nn.ModuleList, want: th.Tensor, avoid: th.Tensor) -> th.Tensor:
    """Every block's attention bias from the goal's pair relations (b, blocks · heads, n, n):
    ``layer`` of ``[want[i, j], want[j, i], avoid[i, j], avoid[j, i]]``, as `_pair_bias`."""
    weight = th.cat([layer.weight for layer in layers])  # (blocks · heads, 4 · parts)
    offset = th.cat([layer.bias for layer in layers])
    p = want.shape[-1]
    direct = want @ weight[:, :p].T + avoid @ weight[:, 2 * p : 3 * p].T
    reverse = want @ weight[:, p : 2 * p].T + avoid @ weight[:, 3 * p :].T
    return (direct + reverse.transpose(1, 2) + offset).permute(0, 3, 1, 2)


def _split(features: th.Tensor, d: int, k: int = _K) -> tuple[th.Tensor, th.Tensor]:
    """(the E tokens (b, E, d), the pooled context (b, d)) of the features (`k` slots)."""
    b, e = features.shape[0], n_entities(k)
    return features[:, : e * d].reshape(b, e, d), features[:, e * d : (e + 1) * d]


def _goal_place(features: th.Tensor, d: int, k: int) -> th.Tensor | None:
    """The goal-conditioned encoder's place scores (b, k · (k + R)), else None."""
    start = (n_entities(k) + 1) * d
    return features[:, start:] if features.shape[1] > start else None


def _first_layer(layer: nn.Linear, *parts: th.Tensor) -> th.Tensor:
    """``layer(cat(parts, -1))`` without the concatenation: each part through its block of the
    weight (the parts broadcast against each other only after the product)."""
    out = None
    start = 0
    for x in parts:
        w = layer.weight[:, start : start + x.shape[-1]]
        start += x.shape[-1]
        y = x @ w.T
        out = y if out is None else out + y
    assert out is not None and start == layer.in_features
    return out + layer.bias


class SlotActionHead(nn.Module):
    """Logits of every objects-interface index from the tokens it names (module docstring).

    Each head's first layer reads a concatenation of tokens (object, support or space, their
    product, the pooled context); it is computed per token and broadcast over the pairs
    (`_first_layer`), the same function as on the concatenation at a fraction of the cost:
    a place scores K·(K+R) pairs, but only the product term is per pair.
    """

    def __init__(self, d: int, k: int = _K) -> None:
        super().__init__()
        self.d, self.k = d, k
        self.pick = nn.Sequential(nn.Linear(2 * d, d), nn.ReLU(), nn.Linear(d, _M * _G))
        self.place = nn.Sequential(nn.Linear(4 * d, d), nn.ReLU(), nn.Linear(d, 1))
        self.slide = nn.Sequential(nn.Linear(3 * d, d), nn.ReLU(), nn.Linear(d, _M * _G))

    def last_layers(self) -> tuple[nn.Linear, ...]:
        """The layers whose small initial weights make the first policy near-uniform."""
        return self.pick[-1], self.place[-1], self.slide[-1]

    def forward(self, features: th.Tensor) -> th.Tensor:
        obj, supports, space, ctx = _tokens(features, self.d, self.k)
        pick = _picks(self.pick, obj, ctx)
        oi, sj = obj[:, :, None], supports[:, None]  # (b, K, 1, d), (b, 1, K + R, d)
        hidden = _first_layer(self.place[0], oi, sj, oi * sj, ctx[:, None]).relu()
        place = self.place[2](hidden).reshape(obj.shape[0], -1)  # (i, j)
        place = _with_goal(place, features, self.d, self.k)
        return _logits(pick, place, _slides(self.slide, oi, space, ctx), self.k)


class SlotPointerHead(nn.Module):
    """`SlotActionHead` with a place scored as a pointer: the object's query (from its token
    and the pooled context) dotted with each support's key, instead of an MLP over every
    (object, support) pair. The pair MLP was most of a training step's time (its hidden layer
    is K·(K+R)·d per sample, benchmarks/train_speed.py); the pointer's pairs are one product.
    Picks and slides are scored as in `SlotActionHead` (the same layers, the same order)."""

    def __init__(self, d: int, k: int = _K) -> None:
        super().__init__()
        self.d, self.k = d, k
        self.pick = nn.Sequential(nn.Linear(2 * d, d), nn.ReLU(), nn.Linear(d, _M * _G))
        self.query = nn.Sequential(nn.Linear(2 * d, d), nn.ReLU(), nn.Linear(d, d))
        self.key = nn.Sequential(nn.Linear(d, d), nn.ReLU(), nn.Linear(d, d))
        self.slide = nn.Sequential(nn.Linear(3 * d, d), nn.ReLU(), nn.Linear(d, _M * _G))

    def last_layers(self) -> tuple[nn.Linear, ...]:
        """The layers whose small initial weights make the first policy near-uniform."""
        return self.pick[-1], self.query[-1], self.slide[-1]

    def forward(self, features: th.Tensor) -> th.Tensor:
        obj, supports, space, ctx = _tokens(features, self.d, self.k)
        pick = _picks(self.pick, obj, ctx)
        query = self.query[2](_first_layer(self.query[0], obj, ctx).relu())  # (b, K, d)
        key = self.key(supports)  # (b, K + R, d)
        place = (query @ key.transpose(1, 2)).reshape(obj.shape[0], -1) / math.sqrt(self.d)
        place = _with_goal(place, features, self.d, self.k)
        slides = _slides(self.slide, obj[:, :, None], space, ctx)
        return _logits(pick, place, slides, self.k)


def _tokens(
    features: th.Tensor, d: int, k: int = _K
) -> tuple[th.Tensor, th.Tensor, th.Tensor, th.Tensor]:
    """The object, support and free-space tokens and the pooled context (b, 1, d)."""
    x, g = _split(features, d, k)
    return x[:, :k], x[:, : k + _R], x[:, k + _R :], g[:, None]


def _with_goal(place: th.Tensor, features: th.Tensor, d: int, k: int) -> th.Tensor:
    """The place logits (i, j) plus the goal-conditioned encoder's pair scores, if any."""
    goal = _goal_place(features, d, k)
    return place if goal is None else place + goal


def _picks(pick: nn.Sequential, obj: th.Tensor, ctx: th.Tensor) -> th.Tensor:
    """The pick logits (i, m, g), flattened per sample."""
    return pick[2](_first_layer(pick[0], obj, ctx).relu()).reshape(obj.shape[0], -1)


def _slides(slide: nn.Sequential, oi: th.Tensor, space: th.Tensor, ctx: th.Tensor) -> th.Tensor:
    """The slide logits (i, m, g, s), flattened per sample; `oi`: the object tokens
    (b, K, 1, d)."""
    hidden = _first_layer(slide[0], oi, space[:, None], ctx[:, None]).relu()
    slides = slide[2](hidden)  # (i, s, m*g) -> (i, m, g, s)
    return slides.permute(0, 1, 3, 2).reshape(oi.shape[0], -1)


def _logits(pick: th.Tensor, place: th.Tensor, slide: th.Tensor, k: int = _K) -> th.Tensor:
    logits = th.cat([pick, place, slide], 1)
    assert logits.shape[1] == n_actions(k)
    return logits


#: the slot policy's action heads by the name of its ``head`` keyword ("pairs" for a model
#: saved without one)
HEADS: dict[str, type[nn.Module]] = {"pairs": SlotActionHead, "pointer": SlotPointerHead}


class _Value(nn.Module):
    def __init__(self, d: int, k: int = _K) -> None:
        super().__init__()
        self.d, self.k = d, k
        self.net = nn.Sequential(nn.Linear(d, d), nn.ReLU(), nn.Linear(d, 1))

    def forward(self, features: th.Tensor) -> th.Tensor:
        return self.net(_split(features, self.d, self.k)[1])


class SlotPolicy(_TrainedKeys, MaskableMultiInputActorCriticPolicy):
    """MaskablePPO's policy over the objects interface: `SlotEncoder` and the slot heads."""

    utamp_algo = "maskable-ppo"

    def __init__(self, *args: Any, head: str = "pairs", **kwargs: Any) -> None:
        if head not in HEADS:
            raise ValueError(f"unknown slot head {head!r}; valid: {', '.join(HEADS)}")
        self.head = head
        kwargs.setdefault("features_extractor_class", SlotEncoder)
        kwargs["net_arch"] = []  # the heads read the tokens themselves
        super().__init__(*args, **kwargs)
        use_fast_masked(self)  # the same distribution, normalised without a slow path

    def _build(self, lr_schedule: Any) -> None:
        super()._build(lr_schedule)
        d, k = self.features_extractor.d_model, self.features_extractor.k
        self.action_net = HEADS[self.head](d, k)
        self.value_net = _Value(d, k)
        for module in (*self.action_net.modules(), *self.value_net.modules()):
            self.init_weights(module, gain=np.sqrt(2))  # orthogonal, as SB3 does
        for last in self.action_net.last_layers():
            self.init_weights(last, gain=0.01)  # near-uniform first policy
        self.init_weights(self.value_net.net[-1], gain=1.0)
        self.optimizer = self.optimizer_class(
            self.parameters(), lr=lr_schedule(1), **self.optimizer_kwargs
        )

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return {**super()._get_constructor_parameters(), "head": self.head}
