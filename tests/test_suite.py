"""Suite-wide conformance, in the spirit of dm_control's ``suite_test``.

Over {procedural house, scan folder, graph proxy} × every registered environment (gymnasium
ids and ``dm_env`` action sets; the GO1's envs drive the legged body, the others the point
body): every MuJoCo element of the worlds drawn is named, observations are finite and match
their spaces, the same seed gives identical rollouts, and consecutive observations share no
memory. And the import boundary: the core never imports gymnasium, torch, ray or dm_control.
"""

from __future__ import annotations

import itertools
import shutil
import subprocess
import sys

import mujoco
import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")
pytest.importorskip("dm_env")

from havln_mj import dmenv  # noqa: E402
from havln_mj.gym import ENV_IDS  # noqa: E402
from havln_mj.scene.scan import load_scan  # noqa: E402

SMALL = {"width": 32, "height": 24, "depth": True, "human_mask": True}
STEPS = 4
_OBJECTS = {
    "body": mujoco.mjtObj.mjOBJ_BODY,
    "geom": mujoco.mjtObj.mjOBJ_GEOM,
    "site": mujoco.mjtObj.mjOBJ_SITE,
    "camera": mujoco.mjtObj.mjOBJ_CAMERA,
    "light": mujoco.mjtObj.mjOBJ_LIGHT,
    "joint": mujoco.mjtObj.mjOBJ_JOINT,
    "actuator": mujoco.mjtObj.mjOBJ_ACTUATOR,
    "mesh": mujoco.mjtObj.mjOBJ_MESH,
}
_SIZES = {"body": "nbody", "geom": "ngeom", "site": "nsite", "camera": "ncam", "light": "nlight"}
_SIZES |= {"joint": "njnt", "actuator": "nu", "mesh": "nmesh"}


@pytest.fixture(scope="module", params=["procedural", "folder", "proxy"])
def scene(request, tmp_path_factory, shared_data_or_none):
    """Keyword arguments that put an environment's episodes in one kind of scene."""
    if request.param == "procedural":
        return {"scenes": ["proc-0"], "episodes_per_scene": 3}
    if request.param == "folder":
        folder = tmp_path_factory.mktemp("scan") / "my-house"
        shutil.copytree(load_scan("proc-3").folder, folder)
        return {"scenes": [str(folder)], "episodes_per_scene": 3}
    if shared_data_or_none is None:
        pytest.skip("graph proxies need real connectivity graphs (../shared/data)")
    data = shared_data_or_none
    return {
        "dataset": data / "r2r" / "R2R_val_seen.json",
        "connectivity_dir": data / "mp3d_connectivity",
        "scenes": ["17DRP5sb8fy"],
    }


@pytest.fixture(scope="module")
def shared_data_or_none(request):
    try:
        return request.getfixturevalue("shared_data")
    except pytest.skip.Exception:
        return None


def _gym_rollout(env_id: str, kwargs: dict, seed: int) -> tuple[list, object]:
    env = gym.make(env_id, **SMALL, **kwargs)
    env.action_space.seed(seed)
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for _ in range(STEPS):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert np.isfinite(reward)
        out.append(obs)
        if terminated or truncated:
            out.append(env.reset()[0])
    sim = env.unwrapped._sim
    return out, (env, sim)


def _dm_rollout(action_set: str, kwargs: dict, seed: int) -> tuple[list, object]:
    env = dmenv.load(action_set, seed=seed, **SMALL, **kwargs)
    rng = np.random.default_rng(seed)
    out = [env.reset().observation]
    for _ in range(STEPS):
        ts = env.step(int(rng.integers(env.action_spec().num_values)))
        assert ts.first() or np.isfinite(ts.reward)
        out.append(ts.observation)
    return out, (env, env.core.sim)


def _unnamed(model: mujoco.MjModel) -> list[str]:
    missing = []
    for kind, obj in _OBJECTS.items():
        for i in range(getattr(model, _SIZES[kind])):
            if kind == "body" and i == 0:
                continue  # the world body
            if not mujoco.mj_id2name(model, obj, i):
                missing.append(f"{kind} {i}")
    return missing


ENVS = [("gym", env_id) for env_id in ENV_IDS] + [("dm", s) for s in dmenv.ACTION_SETS]


@pytest.mark.parametrize(("api", "name"), ENVS, ids=[f"{a}-{n}" for a, n in ENVS])
def test_environment_conformance(api, name, scene):
    rollout = _gym_rollout if api == "gym" else _dm_rollout
    first, (env, sim) = rollout(name, scene, seed=3)
    space = env.observation_space if api == "gym" else None
    spec = env.observation_spec() if api == "dm" else None
    model, _ = sim.draw(0)
    assert _unnamed(model) == [], "every MuJoCo element is named"
    for obs in first:
        for key, value in obs.items():
            assert np.all(np.isfinite(np.asarray(value, float))), key
        if space is not None:
            assert obs in space
        else:
            for key, value in obs.items():
                spec[key].validate(value)
    for a, b in itertools.pairwise(first):
        for key, value in a.items():
            if isinstance(value, np.ndarray):
                assert not np.shares_memory(value, b[key]), key
    env.close()
    again, (env2, _) = rollout(name, scene, seed=3)
    env2.close()
    assert len(again) == len(first)
    for a, b in zip(first, again, strict=True):
        assert a.keys() == b.keys()
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_the_core_imports_no_learning_or_rl_framework():
    code = (
        "import sys\n"
        "import havln_mj, havln_mj.sim.simulator, havln_mj.tasks.step, havln_mj.tasks.experts\n"
        "import havln_mj.tasks.episode_env, havln_mj.run, havln_mj.cli, havln_mj.viewer\n"
        "banned = {'gymnasium', 'torch', 'ray', 'dm_control', 'dm_env'} & set(sys.modules)\n"
        "assert not banned, banned\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
