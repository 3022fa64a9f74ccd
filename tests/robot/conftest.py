"""Shared pieces of the GO1 tests."""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import pytest

from havln_mj.robot.go1 import Go1Body, add_go1


def _go1_on(spec: mujoco.MjSpec, controller: str) -> Go1Body:
    add_go1(spec)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)  # geometry in place for the height scan
    return Go1Body(model, data, controller=controller)


@pytest.fixture
def go1_on() -> Callable[[mujoco.MjSpec, str], Go1Body]:
    """``go1_on(spec, controller)``: a GO1 added to a course, compiled, its geometry placed."""
    return _go1_on
