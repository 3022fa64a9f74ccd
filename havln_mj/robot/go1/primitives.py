"""The GO1 as a navigation agent: ``forward(d)`` and ``turn(theta)`` closed on a state estimate.

Each primitive runs the trot at physics rate (500 Hz by default) under an outer loop: forward
is P on the remaining distance (clipped to a speed floor and cap) while holding the start
heading and lateral offset; turn is P on the remaining yaw while holding the start position.
On reaching the target the gait brings every foot home, then the robot stands ``settle``
seconds before the result is measured. A fall (trunk tipped or low) or a time-out ends a
primitive early with a flag. ``on_tick(sim_time)`` runs every ``tick_period`` of physics time
(20 Hz by default) so callers can move people and check collisions while the robot walks.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import replace

import mujoco

from havln_mj.errors import InvalidArgumentError, did_you_mean
from havln_mj.frames import wrap_heading
from havln_mj.robot.go1 import constants as const
from havln_mj.robot.go1 import steps
from havln_mj.robot.go1.commands import STALL_SECONDS, ForwardCommand, TurnCommand, clip
from havln_mj.robot.go1.crawl import CrawlGait
from havln_mj.robot.go1.estimator import ESTIMATES, OdometryEstimator, TruthEstimator, quat_yaw
from havln_mj.robot.go1.footholds import standing_pose
from havln_mj.robot.go1.gains import Go1Gains, load_gains
from havln_mj.robot.go1.gait import TrotGait
from havln_mj.robot.go1.height_scan import HeightScan
from havln_mj.robot.go1.learned import LearnedGait, LearnedPolicy, PolicySpec, load_policy
from havln_mj.robot.go1.results import Go1Pose, PrimitiveResult
from havln_mj.robot.go1.terrain_gait import TerrainGait

OnTick = Callable[[float], None]
MAX_DISTANCE = 10.0  # metres, per forward primitive
MAX_TURN = 2.0 * math.pi  # radians, per turn primitive
MAX_STAND = 600.0  # seconds


def _check_finite(name: str, value: float, limit: float, lo: float | None = None) -> float:
    lo = -limit if lo is None else lo
    if not (isinstance(value, int | float) and math.isfinite(value) and lo <= value <= limit):
        raise InvalidArgumentError(f"{name} must be a number in [{lo}, {limit}], got {value!r}")
    return float(value)


class Go1Body:
    """Controls one attached GO1 (see :func:`havln_mj.robot.go1.model.add_go1`).

    Args:
        model: The compiled world with the robot.
        data: Its data; primitives step it.
        prefix: The robot's attach prefix.
        estimate: ``"truth"`` (simulator pose) or ``"odometry"`` (gyro + leg kinematics, drifts).
        gains: Controller gains (default: ``robots/go1/gains.json``).
        controller: ``"trot"`` (the blind trot, :mod:`~havln_mj.robot.go1.gait`) or
            ``"terrain"`` (the terrain-aware gait, :mod:`~havln_mj.robot.go1.terrain_gait`,
            which reads the collision geometry through its ``scan``), or ``"learned"`` (the
            terrain gait with a learned residual policy, :mod:`~havln_mj.robot.go1.learned`),
            or ``"crawl"`` (the statically stable stair crawl, :mod:`~havln_mj.robot.go1.crawl`:
            it climbs stairs walking forwards and descends them walking backwards, at its own
            slow pace), or ``"hybrid"`` (the trot on level ground, the crawl for a primitive
            whose walk or turn meets a step or a slope, :mod:`~havln_mj.robot.go1.steps`).
            With ``"terrain"`` and ``"learned"``, :meth:`reset` stands the robot on the
            ground as it is (a stair, a ramp); so does the crawl's where the ground under it
            has a step.
        policy: The learned controller's policy (default: the shipped
            ``robots/go1/policy.npz``), or only its
            :class:`~havln_mj.robot.go1.learned.observation.PolicySpec` for a trainer that
            sets the gait's residual itself; ignored by the other controllers.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        prefix: str = "go1/",
        estimate: str = "truth",
        gains: Go1Gains | None = None,
        controller: str = "trot",
        policy: LearnedPolicy | PolicySpec | None = None,
    ) -> None:
        if controller not in const.CONTROLLERS:
            raise InvalidArgumentError(
                f"controller {controller!r} unknown; valid: {', '.join(const.CONTROLLERS)}"
            )
        if estimate not in ESTIMATES:
            raise InvalidArgumentError(
                f"estimate {estimate!r} unknown; valid: {', '.join(ESTIMATES)}"
            )
        names = [model.body(i).name for i in range(model.nbody)]
        trunk = prefix + const.TRUNK
        if trunk not in names:
            trunks = [n for n in names if n.endswith(const.TRUNK)]
            raise InvalidArgumentError(
                f"no GO1 with prefix {prefix!r} (body {trunk!r}) in the model; trunks found: "
                f"{trunks}.{did_you_mean(trunk, trunks)}"
            )
        if model.opt.timestep > 0.0025:
            raise InvalidArgumentError(
                f"the GO1 needs a timestep <= 0.0025 s, the model has {model.opt.timestep}"
            )
        self.model, self.data, self.prefix = model, data, prefix
        self.gains = gains or load_gains()
        self.trunk_id = model.body(trunk).id
        jnt = model.body_jntadr[self.trunk_id]
        if jnt < 0 or model.jnt_type[jnt] != mujoco.mjtJoint.mjJNT_FREE:
            raise InvalidArgumentError(f"body {trunk!r} has no free joint")
        self.qadr = int(model.jnt_qposadr[jnt])
        self.dadr = int(model.jnt_dofadr[jnt])
        self.joint_qadr = [int(model.joint(prefix + n).qposadr[0]) for n in const.JOINTS]
        self.joint_dadr = [int(model.joint(prefix + n).dofadr[0]) for n in const.JOINTS]
        self.act_ids = [model.actuator(prefix + n).id for n in const.ACTUATORS]
        a0 = self.act_ids[0]
        self._act_slice = slice(a0, a0 + 12) if self.act_ids == list(range(a0, a0 + 12)) else None
        self.foot_ids = [model.geom(prefix + n).id for n in const.FOOT_GEOMS]
        gyro = model.sensor(prefix + const.GYRO)
        self.gyro_adr = int(gyro.adr[0])
        self.estimate = estimate
        if estimate == "truth":
            self.est: TruthEstimator = TruthEstimator(model, data, self.qadr, self.dadr)
        else:
            self.est = OdometryEstimator(
                model, data, self.qadr, self.dadr, self.gyro_adr, self.joint_qadr
            )
        self._truth = TruthEstimator(model, data, self.qadr, self.dadr)
        self.controller = controller
        self.terrain = controller in ("terrain", "learned")
        self.hybrid = controller == "hybrid"
        self.crawl = controller == "crawl"  # the crawl walks (the hybrid's choice of the moment)
        self.policy = policy if policy is not None or controller != "learned" else load_policy()
        self.scan = HeightScan(model, data, self.trunk_id)
        self.gait = self._new_gait()
        self.fallen = False
        self._vx = self._vy = self._wz = 0.0  # filtered measured velocity
        self._ix = self._iy = self._iw = 0.0  # velocity-loop integrals
        self.est.reset()

    def _new_gait(self) -> TrotGait | TerrainGait | CrawlGait:
        if self.crawl:
            return CrawlGait(
                self.gains.crawl, self.model, self.data, self.trunk_id, self.joint_qadr,
                self.joint_dadr, self.foot_ids, self.scan,
            )  # fmt: skip
        ground = (self.gains.terrain, self.data, self.est, self.joint_qadr, self.joint_dadr)
        ground += (self.foot_ids, self.scan)
        if self.controller == "learned":
            if isinstance(self.policy, LearnedPolicy):
                return LearnedGait(*ground, self.trunk_id, self.dadr, self.policy)
            return LearnedGait(*ground, self.trunk_id, self.dadr, None, self.policy)
        if self.terrain:
            return TerrainGait(*ground)
        return TrotGait(self.gains)

    # ----------------------------------------------------------------- state

    def pose(self) -> Go1Pose:
        """The controller's pose estimate (ground truth in ``"truth"`` mode)."""
        e = self.est
        return Go1Pose(e.x, e.y, e.z, e.yaw, wrap_heading(const.HALF_PI - e.yaw))

    def true_pose(self) -> Go1Pose:
        """The simulator's trunk pose."""
        x, y, z, *q = self._truth.truth()
        yaw = quat_yaw(*q)
        return Go1Pose(x, y, z, yaw, wrap_heading(const.HALF_PI - yaw))

    def is_fallen(self) -> bool:
        """Whether the trunk is tipped (up axis z < 0.5) or low (< 0.12 m over its feet)."""
        d = self.data
        if d.xmat[self.trunk_id, 8] < const.FALL_UP_Z:
            return True
        lowest = min(d.geom_xpos[g, 2] for g in self.foot_ids) - const.FOOT_RADIUS
        return d.xpos[self.trunk_id, 2] - lowest < const.FALL_HEIGHT

    @property
    def measured_vx(self) -> float:
        """The trunk's filtered forward speed from the estimate (m/s)."""
        return self._vx

    @property
    def measured_wz(self) -> float:
        """The trunk's filtered yaw rate from the estimate (rad/s)."""
        return self._wz

    def reset(
        self, x: float, y: float, z_floor: float, heading: float, settle: float = 0.5
    ) -> None:
        """Teleports the robot to stand at a floor point, feet home, then lets it settle.

        Args:
            x: Trunk x (m).
            y: Trunk y (m).
            z_floor: Floor height under the robot (m).
            heading: Heading (rad, 0 = +y, turning right).
            settle: Standing time after the teleport (s; physics time advances).
        """
        for name, v in (("x", x), ("y", y), ("z_floor", z_floor), ("heading", heading)):
            _check_finite(name, v, 1e6)
        _check_finite("settle", settle, MAX_STAND, 0.0)
        yaw = const.HALF_PI - heading
        m, d = self.model, self.data
        a = self.qadr
        d.qpos[a : a + 7] = (
            x,
            y,
            z_floor + self.gains.foot_depth + const.FOOT_RADIUS + 0.002,
            math.cos(yaw / 2),
            0.0,
            0.0,
            math.sin(yaw / 2),
        )
        self.gait = self._new_gait()
        home = TrotGait(self.gains).step(0.0, 0.0, 0.0, 0.0)
        for qa, q in zip(self.joint_qadr, home, strict=True):
            d.qpos[qa] = q
        d.qvel[self.dadr : self.dadr + 6] = 0.0
        for da in self.joint_dadr:
            d.qvel[da] = 0.0
        self._write_ctrl(home)
        mujoco.mj_forward(m, d)
        # Stand on the ground as it is (a stair, a ramp): the crawl only where it is uneven,
        # which is also where the hybrid crawls.
        uneven = (self.crawl or self.hybrid) and self.meets_step()
        if self.hybrid:
            self._use_crawl(uneven)
        if self.terrain or uneven:
            top = z_floor + const.STAND_HEIGHT
            if self.terrain:
                z, pitch, home = self.gait.standing_pose(x, y, yaw, top)
            else:
                ground = functools.partial(self.scan.height, top=top)
                z, pitch, home = standing_pose(ground, x, y, yaw, top, self.gains.terrain)
            d.qpos[a + 2] = z + 0.002
            w = (math.cos(yaw / 2), math.sin(yaw / 2))
            p = (math.cos(pitch / 2), math.sin(pitch / 2))
            d.qpos[a + 3 : a + 7] = (w[0] * p[0], -w[1] * p[1], w[0] * p[1], w[1] * p[0])
            for qa, q in zip(self.joint_qadr, home, strict=True):
                d.qpos[qa] = q
            self._write_ctrl(home)
            mujoco.mj_forward(m, d)
        self.fallen = False
        self._vx = self._vy = self._wz = 0.0
        self._ix = self._iy = self._iw = 0.0
        self.est.reset()
        self._truth.reset()
        if self.terrain or self.crawl:
            self.gait.reset()
        if settle > 0:
            self.stand(settle)

    def _write_ctrl(self, q: list[float]) -> None:
        if self._act_slice is not None:
            self.data.ctrl[self._act_slice] = q
        else:
            self.data.ctrl[self.act_ids] = q

    # ------------------------------------------------------------ primitives

    def stand(self, seconds: float, *, on_tick: OnTick | None = None) -> PrimitiveResult:
        """Stands still (feet home) for ``seconds`` of physics time."""
        seconds = _check_finite("seconds", seconds, MAX_STAND, 0.0)
        end = self.data.time + seconds - 1e-9

        def command(hold: bool) -> tuple[float, float, float, bool]:
            return 0.0, 0.0, 0.0, self.data.time >= end

        return self._run("stand", 0.0, command, seconds + 1.0, on_tick, walk=False)

    def forward(self, distance: float, *, on_tick: OnTick | None = None) -> PrimitiveResult:
        """Walks ``distance`` metres along the current heading (negative walks backwards).

        Returns when the estimate is within ``forward_stop`` of the target and the robot
        stands again, on a fall, or after ``2 + |distance| / forward_v_min`` seconds.
        """
        distance = _check_finite("distance", distance, MAX_DISTANCE)
        if self.hybrid:
            self._use_crawl(self.meets_step(distance))
        g = self.gains
        v_max = g.odometry_v_max if self.estimate == "odometry" else g.forward_v_max
        stall, floor = (
            (g.crawl.stall_time, g.crawl.speed_floor)
            if self.crawl
            else (STALL_SECONDS, max(g.forward_v_min, 1e-3))
        )
        command = ForwardCommand(self, distance, v_max, stall)
        timeout = 2.0 + abs(distance) / floor
        result = self._run("forward", distance, command, timeout, on_tick)
        return replace(result, timed_out=True) if command.stall.stalled else result

    def turn(self, theta: float, *, on_tick: OnTick | None = None) -> PrimitiveResult:
        """Turns in place by ``theta`` radians of heading (positive turns right).

        Returns when the estimated heading is within ``turn_stop`` of the target and the
        robot stands again, on a fall, or after ``2 + |theta| / turn_w_min`` seconds.
        """
        theta = _check_finite("theta", theta, MAX_TURN)
        if self.hybrid:
            self._use_crawl(self.meets_step())
        g = self.gains
        stall, floor = (
            (g.crawl.stall_time, g.crawl.turn_floor)
            if self.crawl
            else (STALL_SECONDS, max(g.turn_w_min, 1e-3))
        )
        command = TurnCommand(self, theta, stall)
        timeout = 2.0 + abs(theta) / floor
        result = self._run("turn", theta, command, timeout, on_tick)
        return replace(result, timed_out=True) if command.stall.stalled else result

    def meets_step(self, distance: float | None = None, heading: float | None = None) -> bool:
        """Whether a walk of ``distance`` m (None: a turn in place) from here meets a step.

        See :func:`~havln_mj.robot.go1.steps.meets_step`; ``heading`` is the walk's (rad;
        default the robot's).
        """
        p = self.true_pose()
        yaw = p.yaw if heading is None else const.HALF_PI - heading
        return steps.meets_step(self.scan, self.gains.crawl, p.x, p.y, p.z, yaw, distance)

    def crawls(self, distance: float | None, heading: float | None = None) -> bool:
        """Whether that walk (or turn, ``distance`` None) would be the crawl's.

        Always with ``"crawl"``, never with the trots; with ``"hybrid"`` where it
        :meth:`meets_step`.
        """
        return self.meets_step(distance, heading) if self.hybrid else self.crawl

    def _use_crawl(self, crawl: bool) -> None:
        """The hybrid's gait for the next primitive (a switch happens standing)."""
        if crawl != self.crawl:
            self.crawl = crawl
            self.gait = self._new_gait()

    # ------------------------------------------------------------- the loop

    def _run(
        self,
        kind: str,
        target: float,
        command: Callable[[bool], tuple[float, float, float, bool]],
        timeout: float,
        on_tick: OnTick | None,
        walk: bool = True,
    ) -> PrimitiveResult:
        """Runs the control loop until ``command`` says done, then stops and settles.

        ``command(hold)`` returns the twist (vx, vy, wz) in the trunk frame and whether the
        target is reached; ``hold`` asks for the gentle twist used while the feet come down.
        """
        m, d, g, e = self.model, self.data, self.gains, self.est
        t0 = d.time
        truth0 = self.true_pose()
        est0 = self.pose()
        steps = 0
        timed_out = False
        if self.fallen or self.is_fallen():
            self.fallen = True
            return self._result(kind, target, truth0, est0, t0, steps, False)
        n = (g.crawl if self.crawl else g.terrain if self.terrain else g).control_decimation
        dt = n * m.opt.timestep
        alpha = min(1.0, dt / g.velocity_filter) if g.velocity_filter > 0 else 1.0
        self._ix = self._iy = self._iw = 0.0
        stage = "walk" if walk else "stand"
        settle_end = math.inf
        next_tick = t0 + g.tick_period
        next_fall_check = t0  # falls are checked at 100 Hz: plenty, and a tenth of the cost
        deadline = t0 + timeout
        gait = self.gait
        if walk:
            gait.start()
        while True:
            e.update(dt, gait.stance if gait.walking else [True] * 4)
            self._vx += alpha * (e.vx - self._vx)
            self._vy += alpha * (e.vy - self._vy)
            self._wz += alpha * (e.wz - self._wz)
            if stage in ("walk", "stand", "stopping"):
                vx, vy, wz, done = command(stage == "stopping")
                if stage != "stopping" and (done or d.time >= deadline):
                    timed_out = not done
                    gait.request_stop()
                    self._iw = 0.0  # the turn's yaw-rate integral would carry it past
                    stage = "stopping"
            if stage == "stopping" and not gait.walking:
                stage = "settle"
                settle_end = d.time + (g.settle if walk else 0.0)
            if stage == "settle" and d.time >= settle_end - 1e-9:
                break
            if gait.walking and not (self.terrain or self.crawl):  # these hold speed themselves
                self._integrate(vx, vy, wz, dt)
            if gait.walking:
                q = gait.step(
                    dt, vx + self._ix, vy + self._iy, wz + self._iw, self._vx - vx, self._vy - vy
                )
            else:
                q = gait.step(dt, 0.0, 0.0, 0.0)
            self._write_ctrl(q)
            mujoco.mj_step(m, d, n)
            steps += n
            if d.time >= next_fall_check - 1e-9:
                next_fall_check = d.time + 0.01
                if self.is_fallen():
                    self.fallen = True
                    gait.walking = False
                    break
            if on_tick is not None and d.time >= next_tick - 1e-9:
                on_tick(d.time)
                next_tick += g.tick_period
            if d.time > deadline + 2.0:  # the stop itself cannot finish (should not happen)
                timed_out = True
                break
        e.update(dt, [True] * 4)
        return self._result(kind, target, truth0, est0, t0, steps, timed_out)

    def _integrate(self, vx: float, vy: float, wz: float, dt: float) -> None:
        """Grows the velocity loops' integrals on the twist error, clipped to their limits."""
        g = self.gains
        lim_v, lim_w = g.integral_limit_velocity, g.integral_limit_yaw_rate
        self._ix = clip(self._ix + g.ki_velocity * (vx - self._vx) * dt, -lim_v, lim_v)
        self._iy = clip(self._iy + g.ki_velocity * (vy - self._vy) * dt, -lim_v, lim_v)
        self._iw = clip(self._iw + g.ki_yaw_rate * (wz - self._wz) * dt, -lim_w, lim_w)

    def _result(
        self,
        kind: str,
        target: float,
        truth0: Go1Pose,
        est0: Go1Pose,
        t0: float,
        steps: int,
        timed_out: bool,
    ) -> PrimitiveResult:
        return PrimitiveResult.between(
            kind,
            target,
            (truth0, self.true_pose()),
            (est0, self.pose()),
            duration=self.data.time - t0,
            steps=steps,
            fell=self.fallen,
            timed_out=timed_out,
        )
