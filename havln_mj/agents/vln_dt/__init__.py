"""VLN-DT: HA-VLN's decision transformer, trained offline on random walks by behaviour cloning.

Each step ``t`` of a rollout gives three tokens, ``R_t, s_t, a_t``:

* ``R_t``, the return-to-go: the sum of the rewards from step ``t`` to the end of the rollout
  (at test time: a target, 5 in the paper, minus the rewards collected so far);
* ``s_t``, the state: the observation (view feature and the agent's own inputs, opaque here)
  fused with the instruction, which a :class:`~havln_mj.agents.text.TextTransformer` encodes
  once per sequence. ``"attention"`` fusion lets the projected observation query the
  instruction's tokens by cross-attention; ``"concat"`` joins it with the pooled instruction;
* ``a_t``, the action taken.

A timestep embedding is added to all three. A causal transformer reads
``R_1, s_1, a_1, R_2, s_2, a_2, …`` and the action ``a_t`` is predicted from the output at
``s_t``, which has seen ``R_{≤t}``, ``s_{≤t}`` and ``a_{<t}``. Training is cross-entropy on
the logged actions over windows of at most ``context`` steps (:func:`~.sample_windows`,
:func:`~.dt_loss`); :class:`~.DTPolicy` acts one step at a time with the return-to-go bookkeeping
``R_{t+1} = R_t − r_t``.

HA3D's VLN-DT (``reference/ha3d_facts.md`` §5, §9) is a 12-layer minGPT over ResNet-152 and
BART features with a 5-step window; this one follows the HA-VLN paper's numbers instead: a
15-step window and an initial return-to-go of 5, on 10⁴ random walks of at most 30 steps.
"""

from havln_mj.agents.vln_dt.model import FORWARD_KEYS, FUSIONS, DecisionTransformer, DTConfig
from havln_mj.agents.vln_dt.policy import DTPolicy
from havln_mj.agents.vln_dt.windows import DTDataset, dt_loss, returns_to_go, sample_windows

__all__ = [
    "FORWARD_KEYS",
    "FUSIONS",
    "DTConfig",
    "DTDataset",
    "DTPolicy",
    "DecisionTransformer",
    "dt_loss",
    "returns_to_go",
    "sample_windows",
]
