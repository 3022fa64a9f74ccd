"""Many GO1s on the training courses, stepped one after another in one process.

Each robot has its own ``MjData`` on the compiled course of its terrain level
(:mod:`~havln_mj.train_go1.terrains`) and a :class:`~havln_mj.robot.go1.primitives.Go1Body` with the
learned controller whose residual the trainer sets. A robot starts at the foot of the flight
or on the landing, facing +x, and walks +x at a commanded speed with heading and lateral offset
held (as the ``forward`` primitive does), or turns in place. An episode ends in a fall or after
``episode_seconds`` (a time-out, which the learner bootstraps); then the curriculum moves the
robot's level and it starts over.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from havln_mj.robot.go1 import Go1Body, load_gains
from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1.frames import roll_pitch
from havln_mj.robot.go1.learned import LearnedGait, PolicySpec
from havln_mj.train_go1.config import TrainConfig
from havln_mj.train_go1.curriculum import Curriculum
from havln_mj.train_go1.rewards import reward
from havln_mj.train_go1.terrains import KINDS, WIDTH, Course, build_courses

K_LATERAL, K_YAW, V_LATERAL, W_HOLD = 1.0, 2.0, 0.2, 1.0  # the forward primitive's holds


@dataclass
class _Robot:
    """One robot's episode."""

    body: Go1Body
    key: tuple[str, int, float]
    course: Course
    command: tuple[float, float, float] = (0.0, 0.0, 0.0)  # vx, (unused vy), wz
    turning: bool = False
    t: float = 0.0
    x0: float = 0.0
    paced: float = 0.0
    ref: list[float] = field(default_factory=list)
    v: tuple[float, float] = (0.0, 0.0)  # filtered measured velocity
    feet: np.ndarray = field(default_factory=lambda: np.zeros((4, 2)))


class Go1Envs:
    """``num_envs`` robots with a terrain curriculum.

    Args:
        cfg: The training configuration.
        rng: The run's generator (every random draw comes from it).
        spec: The observation layout.
        levels: Each robot's terrain level (default: random up to ``max_init_level``).
    """

    def __init__(
        self,
        cfg: TrainConfig,
        rng: np.random.Generator,
        spec: PolicySpec,
        levels: np.ndarray | None = None,
    ) -> None:
        self.cfg, self.rng, self.spec = cfg, rng, spec
        e = cfg.env
        self.gains = load_gains()
        self.dt = spec.decimation * const.TIMESTEP
        self.courses = build_courses(e)
        self.kinds = [
            KINDS[1] if rng.random() < e.ramp_share else KINDS[0] for _ in range(e.num_envs)
        ]
        start = rng.integers(0, e.max_init_level + 1, e.num_envs) if levels is None else levels
        self.curriculum = Curriculum(cfg.curriculum, e.levels, start, rng)
        self.robots: list[_Robot | None] = [None] * e.num_envs
        self.finished: list[dict] = []  # episodes ended since the last drain
        self.term_sums: dict[str, float] = {}  # weighted reward terms summed since the drain
        self.term_steps = 0
        self._obs = np.zeros((e.num_envs, spec.obs_size))
        for i in range(e.num_envs):
            self._start(i)

    @property
    def num_envs(self) -> int:
        """Number of robots."""
        return self.cfg.env.num_envs

    def observations(self) -> np.ndarray:
        """The current observation of every robot, ``(num_envs, obs_size)``."""
        return self._obs.copy()

    # -------------------------------------------------------------- episodes

    def _start(self, i: int) -> None:
        e, rng = self.cfg.env, self.rng
        kind, level = self.kinds[i], int(self.curriculum.level[i])
        tread = float(rng.choice(e.treads)) if kind == "stairs" else 0.0
        key = (kind, level, tread)
        course = self.courses[key]
        old = self.robots[i]
        if old is not None and old.key == key:
            body = old.body
        else:
            body = Go1Body(
                course.model,
                mujoco.MjData(course.model),
                gains=self.gains,
                controller="learned",
                policy=self.spec,
            )
            body.scan = course.scan
        on_top = course.rise > 0 and rng.random() < 0.5
        x = course.top_start if on_top else -0.6
        x += float(rng.uniform(-0.1, 0.1))
        y = float(rng.uniform(-0.2, 0.2))
        heading = math.pi / 2 + float(rng.uniform(-0.1, 0.1))
        body.reset(x, y, course.rise if on_top else 0.0, heading, settle=0.2)
        r = _Robot(body, key, course)
        r.turning = rng.random() < e.turn_share
        if r.turning:
            r.command = (0.0, 0.0, float(rng.choice((-1, 1)) * rng.uniform(*e.turn_rate)))
        else:
            r.command = (float(rng.uniform(*e.speed)), 0.0, 0.0)
        r.x0 = body.true_pose().x
        r.feet = self._feet(body)
        self.robots[i] = r
        body.gait.start()
        r.ref = self._tick(r)
        self._obs[i] = body.gait.observe(r.ref)

    def _twist(self, r: _Robot) -> tuple[float, float, float]:
        """The commanded twist now: the episode's, with heading and lateral offset held."""
        if r.turning:
            return r.command
        e = r.body.est
        vy = float(np.clip(-K_LATERAL * e.y, -V_LATERAL, V_LATERAL))
        wz = float(np.clip(-K_YAW * math.remainder(e.yaw, 2 * math.pi), -W_HOLD, W_HOLD))
        return r.command[0], vy, wz

    def _tick(self, r: _Robot) -> list[float]:
        """Updates the estimate and the velocity filter, then advances the gait one tick."""
        body, g = r.body, self.gains
        gait: LearnedGait = body.gait
        dt = g.terrain.control_decimation * const.TIMESTEP
        body.est.update(dt, gait.stance if gait.walking else [True] * 4)
        a = min(1.0, dt / g.velocity_filter) if g.velocity_filter > 0 else 1.0
        e = body.est
        r.v = (r.v[0] + a * (e.vx - r.v[0]), r.v[1] + a * (e.vy - r.v[1]))
        vx, vy, wz = self._twist(r)
        return gait.reference(dt, vx, vy, wz, r.v[0] - vx, r.v[1] - vy)

    @staticmethod
    def _feet(body: Go1Body) -> np.ndarray:
        return body.data.geom_xpos[body.foot_ids, :2].copy()

    # ------------------------------------------------------------------ step

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Applies one action per robot for one policy period.

        Returns:
            ``(observations, rewards, dones, timeouts)``: observations after the step (a robot
            that ended starts over: its first), rewards, whether each episode ended, and
            whether it ended by time-out (not a fall).
        """
        n = self.num_envs
        rewards, dones, timeouts = np.zeros(n), np.zeros(n, bool), np.zeros(n, bool)
        for i in range(n):
            rewards[i], dones[i], timeouts[i] = self._step_one(i, actions[i])
        return self._obs.copy(), rewards, dones, timeouts

    def _step_one(self, i: int, action: np.ndarray) -> tuple[float, bool, bool]:
        r = self.robots[i]
        body = r.body
        gait: LearnedGait = body.gait
        m, d = body.model, body.data
        steps = self.gains.terrain.control_decimation
        last = gait.action
        gait.action = np.clip(
            np.asarray(action, dtype=np.float64), -self.spec.clip_actions, self.spec.clip_actions
        )
        ref = r.ref
        for k in range(gait.ticks):
            if k:
                ref = self._tick(r)
            body._write_ctrl(gait.targets(ref))
            mujoco.mj_step(m, d, steps)
        r.t += self.dt
        r.paced += gait._v[0] * self.dt  # the gait's pace after its speed cap
        fell = body.is_fallen()
        raw = self._measure(r, last)
        total, terms = reward(self.cfg.reward, raw, self.dt, fell)
        for name, v in terms.items():
            self.term_sums[name] = self.term_sums.get(name, 0.0) + v
        self.term_steps += 1
        y = d.xpos[body.trunk_id, 1]
        timeout = r.t >= self.cfg.env.episode_seconds - 1e-9 or abs(y) > 0.5 * WIDTH - 0.3
        if fell or timeout:
            self._finish(i, r, fell)
            self._start(i)
            return total, True, not fell
        r.ref = self._tick(r)
        self._obs[i] = gait.observe(r.ref)
        return total, False, False

    def _measure(self, r: _Robot, last: np.ndarray) -> dict[str, float]:
        """The unweighted reward terms after a step."""
        body = r.body
        gait: LearnedGait = body.gait
        m, d = body.model, body.data
        rot = d.xmat[body.trunk_id]
        yaw = math.atan2(rot[3], rot[0])
        vel = d.qvel[body.dadr : body.dadr + 6]
        vx = math.cos(yaw) * vel[0] + math.sin(yaw) * vel[1]
        wz = rot[6] * vel[3] + rot[7] * vel[4] + rot[8] * vel[5]
        a = gait.action
        quat = tuple(d.qpos[body.qadr + 3 : body.qadr + 7])
        roll, pitch = roll_pitch(quat)
        feet = self._feet(body)
        speed = np.linalg.norm(feet - r.feet, axis=1) / self.dt
        r.feet = feet
        clear = 0.0
        h_c = self.cfg.reward.clearance_height
        z_top = d.xpos[body.trunk_id, 2]
        for leg, g in enumerate(body.foot_ids):
            if gait.swings[leg] is None:
                continue
            fx, fy, fz = d.geom_xpos[g]
            ground = r.course.scan.height(fx, fy, z_top)
            if math.isfinite(ground):
                clear += max(0.0, h_c - (fz - const.FOOT_RADIUS - ground)) * speed[leg]
        return {
            "lin_vel_error": (vx - gait._v[0]) ** 2,
            "ang_vel_error": (wz - gait.command[2]) ** 2,
            "upright": roll**2 + (pitch - gait.pitch_ref) ** 2,
            "torque": float(np.sum(d.actuator_force[body.act_ids] ** 2)),
            "action_rate": float(np.sum((a - last) ** 2)),
            "action_size": float(np.sum(a**2)),
            "clearance": clear,
            "collision": float(_collisions(m, d, body)),
        }

    def _finish(self, i: int, r: _Robot, fell: bool) -> None:
        x = r.body.true_pose().x
        progress = (x - r.x0) / max(r.paced, 0.05)
        level = int(self.curriculum.level[i])
        if not r.turning:
            self.curriculum.update(i, progress, fell)
        self.finished.append(
            {
                "kind": r.key[0],
                "level": level,
                "turning": r.turning,
                "fell": fell,
                "progress": progress,
                "success": (not fell) and progress >= self.cfg.curriculum.promote,
            }
        )

    def drain(self) -> tuple[list[dict], dict[str, float]]:
        """The episodes ended since the last call, and each reward term's mean per step."""
        out, self.finished = self.finished, []
        terms = {k: v / max(self.term_steps, 1) for k, v in self.term_sums.items()}
        self.term_sums, self.term_steps = {}, 0
        return out, terms


def _collisions(m: mujoco.MjModel, d: mujoco.MjData, body: Go1Body) -> int:
    """Contacts of the robot's trunk, hips, thighs and upper shins with anything else.

    The feet are meant to touch, and so is the shin's lower half just above them (its
    capsule meets the foot sphere and brushes the ground in a normal stance).
    """
    if not d.ncon:
        return 0
    root = m.body_rootid[body.trunk_id]
    n = 0
    for g1, g2 in d.contact.geom[: d.ncon].tolist():
        r1 = m.body_rootid[m.geom_bodyid[g1]] == root
        r2 = m.body_rootid[m.geom_bodyid[g2]] == root
        if r1 != r2 and _counts(m, body, g1 if r1 else g2):
            n += 1
    return n


def _counts(m: mujoco.MjModel, body: Go1Body, geom: int) -> bool:
    if geom in body.foot_ids:
        return False
    b = m.geom_bodyid[geom]
    calves = {m.geom_bodyid[g] for g in body.foot_ids}
    return not (b in calves and m.geom_pos[geom, 2] < -0.1)
