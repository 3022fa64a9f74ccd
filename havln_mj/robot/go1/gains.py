"""Controller gains of the GO1 gaits and primitives, loaded from ``robots/go1/gains.json``."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, fields, is_dataclass, replace
from pathlib import Path

from havln_mj.errors import InvalidArgumentError, MalformedDataError
from havln_mj.paths import asset_path


def _check_numbers(obj) -> None:
    for f in fields(obj):
        value = getattr(obj, f.name)
        if is_dataclass(value):  # a nested gain set checks itself
            continue
        if not (isinstance(value, int | float) and math.isfinite(value)) or (
            value < 0 and f.name != "foot_x_offset"
        ):
            raise InvalidArgumentError(f"gain {f.name} must be a finite number >= 0, got {value!r}")


def _check_decimation(value) -> None:
    if not (isinstance(value, int) and value >= 1):
        raise InvalidArgumentError(f"control_decimation must be an integer >= 1, got {value!r}")


@dataclass(frozen=True)
class TerrainGains:
    """Gains of the terrain-aware gait (:mod:`havln_mj.robot.go1.terrain_gait`; SI units).

    Attributes:
        flat_period: Trot cycle on even ground (s).
        flat_duty: Stance fraction of that cycle.
        flat_height: Trunk height above the feet on even ground (m).
        rough_period: Trot cycle on rough ground (an edge or a climb in the scan ahead).
        rough_duty: Its stance fraction (above 0.5: both diagonal pairs down for a while).
        rough_speed: Speed cap on rough ground and while it lies ahead (m/s).
        rough_height: Trunk height above the feet on rough ground (m).
        clearance: Swing foot above the highest ground it passes over (m).
        min_lift: Swing foot above its lift-off and touch-down points (m).
        touchdown_depth: How far below the ground a swing foot aims (m).
        raibert_gain: Foot placement gain on velocity error (s).
        ref_leak: Rate at which the trunk reference decays toward the estimate (1/s).
        max_lead: Farthest the trunk reference runs ahead of the estimate (m).
        max_yaw_lead: Same for yaw (rad).
        edge_margin: A foothold keeps this far from a riser beside it (m).
        drop_margin: A foothold keeps this far from a drop beside it (m).
        edge_jump: A height step this big between 2 cm samples is an edge (m).
        foothold_shift: Farthest a foothold moves off its Raibert point (m).
        tread_max: Flat pieces shorter than this are stepped on in their middle (m).
        obstacle_rise: Ground this far above the line the feet stand on is an obstacle
            (furniture, a wall), not a step (m).
        rough_hold: The rough rhythm holds until the trunk is this far past the last rough
            ground it had near (m): the hind feet are then past it too.
        stance_follow: Time constant with which a stance foot's reference follows the foot
            along the heading and up, in the rough rhythm (s; 0: it stays where it landed).
        terrain_filter: Time constant of the trunk height and pitch references (s).
        ki_height: Integral gain on the trunk height error (1/s).
        ki_pitch: Integral gain on the pitch error (1/s).
        ki_roll: Integral gain on the roll error (1/s).
        land_band: A swing foot touching lower than this above its goal has landed (m).
        lock_phase: Swing phase after which the foothold no longer moves.
        swing_start: Swing phase at which the foot starts moving horizontally.
        swing_end: Swing phase at which it is over its foothold (then it comes down).
        swing_rate: Most height a swing foot changes per unit of swing phase (m).
        accel: Most the commanded speed changes (m/s²).
        scan_period: Time between looks at the ground ahead (s).
        control_decimation: Physics steps per update of this gait.
    """

    flat_period: float = 0.4
    flat_duty: float = 0.5
    flat_height: float = 0.27
    rough_period: float = 0.6
    rough_duty: float = 0.65
    rough_speed: float = 0.15
    rough_height: float = 0.28
    clearance: float = 0.06
    min_lift: float = 0.06
    touchdown_depth: float = 0.01
    raibert_gain: float = 0.05
    ref_leak: float = 5.0
    max_lead: float = 0.05
    max_yaw_lead: float = 0.1
    edge_margin: float = 0.06
    drop_margin: float = 0.1
    edge_jump: float = 0.025
    foothold_shift: float = 0.16
    tread_max: float = 0.45
    obstacle_rise: float = 0.25
    rough_hold: float = 0.45
    stance_follow: float = 0.08
    terrain_filter: float = 0.1
    ki_height: float = 2.0
    ki_pitch: float = 2.0
    ki_roll: float = 2.0
    land_band: float = 0.03
    lock_phase: float = 0.3
    swing_start: float = 0.15
    swing_end: float = 0.8
    swing_rate: float = 1.2
    accel: float = 1.0
    scan_period: float = 0.04
    control_decimation: int = 2

    def __post_init__(self) -> None:
        _check_numbers(self)
        _check_decimation(self.control_decimation)
        for name, lo, hi in (
            ("flat_duty", 0.4, 0.8),
            ("rough_duty", 0.4, 0.8),
            ("flat_period", 0.2, 2.0),
            ("rough_period", 0.2, 2.0),
        ):
            value = getattr(self, name)
            if not lo <= value <= hi:
                raise InvalidArgumentError(f"{name} must be in [{lo}, {hi}], got {value}")
        if not 0.0 < self.swing_start < self.swing_end < 1.0:
            raise InvalidArgumentError(
                f"need 0 < swing_start < swing_end < 1, got {self.swing_start}, {self.swing_end}"
            )

    def with_(self, **changes: float) -> TerrainGains:
        """A copy with some gains changed."""
        return replace(self, **changes)


@dataclass(frozen=True)
class CrawlGains:
    """Gains of the stair crawl (:mod:`havln_mj.robot.go1.crawl`; SI units).

    Attributes:
        shift_time: Least time the trunk moves over three feet before the fourth lifts (s).
        swing_time: Time a swing takes from lift-off to its foothold (s).
        clearance: Swing foot above the higher of its lift-off and foothold (m).
        height: Trunk height above the ground under the hips (m).
        stride: A foothold's advance on the foot's last one (m).
        lead_reach: Farthest ahead of its hip a leading leg (the front legs walking
            forwards) steps (m).
        trail_reach: The same for a trailing leg (m).
        drop_gap: A foothold keeps this far from the edge of a drop (m).
        face_gap: A foothold keeps this far from the foot of a riser ahead (m).
        edge_jump: A height step this big between 1 cm samples is an edge (m).
        lead: The centre of mass aims this far ahead of a support triangle's centroid (m).
        lift_margin: A foot lifts once the centre of mass is this far inside the other
            three feet's triangle (m).
        target_margin: The centre-of-mass goal keeps this far inside that triangle (m).
        kp_xy: Horizontal stiffness of the centre of mass (N/m).
        kd_xy: Horizontal damping (N·s/m).
        kp_z: Vertical stiffness (N/m).
        kd_z: Vertical damping (N·s/m).
        kp_attitude: Attitude stiffness (N·m/rad).
        kd_attitude: Attitude damping (N·m·s/rad).
        error_cap: Horizontal position error the stiffness acts on at most (m).
        friction: Friction coefficient the stance forces keep within.
        kp_swing: Joint stiffness of a swing leg (N·m/rad).
        kd_swing: Joint damping of a swing leg (N·m·s/rad).
        touch_force: Contact force that lands a swing foot (N).
        ground_window: Half-length of ground averaged under each hip for the trunk pose (m).
        below_foot: A hip may be this much lower than its stance foot's ground (m).
        above_foot: A hip may be this much higher than its stance foot's ground (m).
        below_next: The swing leg's hip may be this much lower than its foothold (m).
        above_next: The swing leg's hip may be this much higher than its foothold (m).
        pitch_rate: Fastest change of the trunk pitch reference (rad/s).
        height_rate: Fastest change of the trunk height reference (m/s).
        yaw_rate: Fastest turn asked of the heading reference (rad/s).
        yaw_lead: The heading reference leads the trunk's by the asked turn rate times this
            (s).
        speed_floor: Slowest walk a forward primitive waits for before it times out (m/s).
        turn_floor: Slowest turn a turn primitive waits for (rad/s).
        stall_time: A primitive without progress for this long has stalled (s).
        control_decimation: Physics steps per controller update.
        trot_step: The hybrid controller trots where no step between neighbouring ground
            samples (:mod:`~havln_mj.robot.go1.steps`) is higher than this (m) and no slope
            steeper than ``trot_grade``, and crawls elsewhere.
        trot_grade: The steepest slope the hybrid controller trots on (rise over run).
    """

    shift_time: float = 0.25
    swing_time: float = 0.45
    clearance: float = 0.06
    height: float = 0.26
    stride: float = 0.16
    lead_reach: float = 0.16
    trail_reach: float = 0.10
    drop_gap: float = 0.12
    face_gap: float = 0.05
    edge_jump: float = 0.03
    lead: float = 0.06
    lift_margin: float = 0.03
    target_margin: float = 0.05
    kp_xy: float = 300.0
    kd_xy: float = 50.0
    kp_z: float = 900.0
    kd_z: float = 60.0
    kp_attitude: float = 300.0
    kd_attitude: float = 25.0
    error_cap: float = 0.08
    friction: float = 0.42
    kp_swing: float = 250.0
    kd_swing: float = 4.0
    touch_force: float = 8.0
    ground_window: float = 0.15
    below_foot: float = 0.08
    above_foot: float = 0.06
    below_next: float = 0.10
    above_next: float = 0.06
    pitch_rate: float = 0.25
    height_rate: float = 0.05
    yaw_rate: float = 0.25
    yaw_lead: float = 0.5
    speed_floor: float = 0.015
    turn_floor: float = 0.05
    stall_time: float = 10.0
    control_decimation: int = 2
    trot_step: float = 0.05
    trot_grade: float = 0.2

    def __post_init__(self) -> None:
        _check_numbers(self)
        _check_decimation(self.control_decimation)


@dataclass(frozen=True)
class Go1Gains:
    """Gait, velocity-loop and primitive gains (SI units, radians).

    Attributes:
        period: Trot cycle (s); each diagonal pair swings for ``(1 - duty) * period``.
        duty: Stance fraction of the cycle.
        swing_height: Foot lift (m).
        foot_depth: Nominal foot depth below the hip joints (m).
        touchdown_depth: How far below nominal a swing foot aims to land (m).
        foot_x_offset: Nominal feet shift forward of the hips (m); trims the trot's drift.
        raibert_gain: Foot placement gain on velocity error (s), for balance.
        ki_velocity: Integral gain of the linear velocity loop (1/s).
        ki_yaw_rate: Integral gain of the yaw-rate loop (1/s); above about 1 its wind-up
            made turns overshoot and spring back by up to 5°.
        integral_limit_velocity: Clip of the velocity integral (m/s).
        integral_limit_yaw_rate: Clip of the yaw-rate integral (rad/s).
        velocity_filter: Time constant of the measured-velocity low-pass (s).
        forward_kp: P gain on remaining distance (1/s).
        forward_v_max: Cruise speed cap (m/s).
        odometry_v_max: Cruise speed cap closed on odometry (m/s): the feet slip more at
            speed, and dead reckoning drifts with them.
        forward_v_min: Speed floor while the target is not reached (m/s).
        forward_accel: Fastest the commanded speed grows (m/s²): a trot asked for its cruise
            speed at once pitches and rolls, and a turn or a long walk after that may fall.
        forward_k_lateral: Lateral offset hold gain (1/s).
        forward_k_yaw: Heading hold gain while walking (1/s).
        forward_stop: Stop when this close to the target distance (m).
        forward_lead: Stop earlier by this many seconds of the measured speed (s).
        turn_kp: P gain on remaining yaw (1/s).
        turn_w_max: Yaw-rate cap (rad/s).
        turn_w_min: Yaw-rate floor while turning (rad/s).
        turn_k_hold: Position hold gain while turning (1/s).
        turn_stop: Stop when this close to the target yaw (rad).
        turn_lead: Stop earlier by this many seconds of the measured yaw rate (s).
        settle: Standing time after the feet are back home (s).
        control_decimation: Physics steps per controller update (1 = 500 Hz control).
        tick_period: Physics time between ``on_tick`` calls (s); at most 1/16.
        terrain: Gains of the terrain-aware gait.
        crawl: Gains of the stair crawl.
    """

    period: float = 0.4
    duty: float = 0.5
    swing_height: float = 0.07
    foot_depth: float = 0.27
    touchdown_depth: float = 0.005
    foot_x_offset: float = 0.0
    raibert_gain: float = 0.05
    ki_velocity: float = 3.0
    ki_yaw_rate: float = 0.0
    integral_limit_velocity: float = 0.25
    integral_limit_yaw_rate: float = 0.6
    velocity_filter: float = 0.05
    forward_kp: float = 2.5
    forward_v_max: float = 0.7
    odometry_v_max: float = 0.5
    forward_v_min: float = 0.1
    forward_accel: float = 1.5
    forward_k_lateral: float = 1.0
    forward_k_yaw: float = 2.0
    forward_stop: float = 0.003
    forward_lead: float = 0.05
    turn_kp: float = 4.0
    turn_w_max: float = 1.2
    turn_w_min: float = 0.4
    turn_k_hold: float = 1.0
    turn_stop: float = 0.0175
    turn_lead: float = 0.05
    settle: float = 0.2
    control_decimation: int = 1
    tick_period: float = 0.05
    terrain: TerrainGains = field(default_factory=TerrainGains)
    crawl: CrawlGains = field(default_factory=CrawlGains)

    def __post_init__(self) -> None:
        _check_numbers(self)
        if not 0.2 <= self.duty <= 0.8:
            raise InvalidArgumentError(f"duty must be in [0.2, 0.8], got {self.duty}")
        if not 0.1 <= self.period <= 2.0:
            raise InvalidArgumentError(f"period must be in [0.1, 2] s, got {self.period}")
        if not 0.15 <= self.foot_depth <= 0.4:
            raise InvalidArgumentError(
                f"foot_depth must be in [0.15, 0.4] m, got {self.foot_depth}"
            )
        _check_decimation(self.control_decimation)
        if not self.forward_accel > 0.0:
            raise InvalidArgumentError(
                f"forward_accel must be > 0 m/s² (the walk would never start), "
                f"got {self.forward_accel}"
            )
        if not 0.0 < self.tick_period <= 1.0 / 16.0:
            raise InvalidArgumentError(
                f"tick_period must be in (0, 1/16] s (on_tick runs at >= 16 Hz), "
                f"got {self.tick_period}"
            )

    def with_(self, **changes) -> Go1Gains:
        """A copy with some gains changed."""
        return replace(self, **changes)


def load_gains(path: str | Path | None = None) -> Go1Gains:
    """Reads gains from a JSON object of ``Go1Gains`` fields (default: the shipped file).

    Keys starting with ``_`` are comments. Missing keys keep their defaults. The object under
    ``"terrain"`` holds :class:`TerrainGains`, the one under ``"crawl"`` :class:`CrawlGains`.

    Raises:
        MalformedDataError: Unknown keys or not a JSON object.
    """
    path = Path(path) if path is not None else asset_path("robots", "go1", "gains.json")
    try:
        raw = json.loads(Path(path).read_text())
    except json.JSONDecodeError as err:
        raise MalformedDataError(f"{path} is not valid JSON: {err}") from err
    if not isinstance(raw, dict):
        raise MalformedDataError(f"{path} must hold a JSON object of gains")
    values = known_fields(raw, Go1Gains, path)
    parts = {}
    for key, cls in (("terrain", TerrainGains), ("crawl", CrawlGains)):
        part = values.pop(key, {})
        if not isinstance(part, dict):
            raise MalformedDataError(f"{path}: {key!r} must be a JSON object of {key} gains")
        parts[key] = cls(**known_fields(part, cls, path))
    return Go1Gains(**values, **parts)


def known_fields(raw: dict, cls: type, where: object) -> dict:
    """``raw`` without its ``_`` comment keys, checked against the fields of dataclass ``cls``.

    Raises:
        MalformedDataError: A key is not a field (``where`` names the source).
    """
    names = {f.name for f in fields(cls)}
    values = {k: v for k, v in raw.items() if not k.startswith("_")}
    unknown = sorted(set(values) - names)
    if unknown:
        raise MalformedDataError(f"{where}: unknown keys {unknown}; valid: {sorted(names)}")
    return values
