"""A learned GO1 controller evaluated with numpy: a residual policy on the terrain gait.

``Go1Body(model, data, controller="learned")`` walks with the shipped policy
(``robots/go1/policy.npz``); ``policy=`` takes another. :mod:`havln_mj.train_go1` trains and
exports policies.
"""

from havln_mj.robot.go1.learned.controller import LearnedGait
from havln_mj.robot.go1.learned.observation import Observer, PolicySpec
from havln_mj.robot.go1.learned.policy import FORMAT_VERSION, LearnedPolicy, load_policy

__all__ = [
    "FORMAT_VERSION",
    "LearnedGait",
    "LearnedPolicy",
    "Observer",
    "PolicySpec",
    "load_policy",
]
