"""The masked categorical distribution of the MaskablePPO policies, normalised cheaply.

Why: sb3-contrib's `MaskableCategorical` sets masked logits to −1e8 and normalises them with
``logsumexp`` (through ``torch.distributions.Categorical``), twice per distribution (the raw
logits, then the masked ones). On CPU, ``torch.exp`` of such large negative numbers leaves
the vectorised path: over the 2,676 logits of the objects interface, with nearly all of them
masked, one ``logsumexp`` of a 256-row minibatch takes ~20 ms instead of ~1.5 ms (measured by
``benchmarks/train_speed.py``). `MaskedCategorical` is the same distribution (same
probabilities, log-probabilities, entropy and gradients, up to float rounding) normalised
once, with ``log_softmax``, whose kernel has no such slow path; argument validation is off
(actions come from the policy itself); samples are drawn by inverting the cumulative
distribution. The policies select it with `use_fast_masked`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch as th
from sb3_contrib.common.maskable.distributions import (
    MaskableCategorical,
    MaskableCategoricalDistribution,
)
from torch.distributions import Distribution

#: the value of a masked logit (sb3-contrib's)
HUGE_NEG = -1e8


class MaskedCategorical(MaskableCategorical):
    """`MaskableCategorical` normalised with one ``log_softmax`` (module docstring)."""

    def __init__(self, logits: th.Tensor, masks: th.Tensor | np.ndarray | None = None) -> None:
        self.masks: th.Tensor | None = None
        self._original_logits = logits
        self.apply_masking(masks)

    def apply_masking(self, masks: th.Tensor | np.ndarray | None) -> None:
        raw = self._original_logits
        if masks is not None:
            self.masks = th.as_tensor(masks, dtype=th.bool, device=raw.device).reshape(raw.shape)
            raw = raw.masked_fill(~self.masks, HUGE_NEG)
        else:
            self.masks = None
        self.__dict__.pop("probs", None)  # a lazy property of the previous logits
        self.logits = raw.log_softmax(-1)
        self._param = self.logits
        self._num_events = raw.size(-1)
        Distribution.__init__(self, raw.size()[:-1], validate_args=False)

    def sample(self, sample_shape: th.Size = th.Size()) -> th.Tensor:  # noqa: B008
        """A draw by inverting the cumulative distribution: the first action whose cumulative
        probability exceeds ``u · total``, ``u ~ U[0, 1)``. A masked action has probability 0
        (its cumulative equals its predecessor's), so it is never the first to exceed; ``u``
        is scaled by 1 − 1e-6 so that the draw stays below the total under rounding. On CPU it
        costs a small fraction of ``torch.multinomial`` or ``exp`` over the 2,676
        objects-interface logits (each ~0.5 ms per rollout step of 8 envs: ``exp`` of the
        masked logits leaves the vectorised path)."""
        probs = self.logits.softmax(-1)
        cdf = probs.expand(th.Size(sample_shape) + probs.shape).cumsum(-1)
        u = th.rand((*cdf.shape[:-1], 1), dtype=cdf.dtype, device=cdf.device)
        u = u * cdf[..., -1:] * (1 - 1e-6)
        return th.searchsorted(cdf, u, right=True).squeeze(-1)


class MaskedCategoricalDistribution(MaskableCategoricalDistribution):
    """sb3-contrib's masked categorical distribution built on `MaskedCategorical`."""

    distribution: MaskedCategorical

    def proba_distribution(self, action_logits: th.Tensor) -> MaskedCategoricalDistribution:
        self.distribution = MaskedCategorical(action_logits.view(-1, self.action_dim))
        return self


def use_fast_masked(policy: Any) -> None:
    """Give a MaskablePPO policy (with a `Discrete` action space) `MaskedCategoricalDistribution`;
    it holds no parameters, so saved models load unchanged."""
    dist = policy.action_dist
    if type(dist) is MaskableCategoricalDistribution:
        policy.action_dist = MaskedCategoricalDistribution(dist.action_dim)
