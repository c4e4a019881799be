"""The chapter-5 mobile robot: a six-wheeled skid-steer base of KURT3D's size.

What the robot has
    A body 45 cm long, 33 cm wide, 47 cm tall (a box from 6 cm to 40 cm above the floor
    and, on top at its front edge, the scanner's head up to 47 cm), 22 kg, on six sphere
    wheels (radius 6 cm) on three axles 13 cm apart, all driven: left wheels one way and
    right wheels the other turn it in place, all alike drive it straight. As on KURT3D,
    the three wheels of a side are coupled (PhysX fixed tendons stand in for the chain).
    It moves through PhysX contacts only; what stops it, tips it or lets it pass is
    whatever PhysX makes of it.

    Its own senses: wheel encoders (the joints' angles, ``revolute_unwrapped`` so that they
    do not wrap) and an IMU: a gyro for the heading and the body's tilt (ideal: no drift, no
    noise). The range scanner lives in ``sim.scanner``, mounted at
    :attr:`MobileRobotConfig.scanner_mount`.

The behaviour (thesis 5.3.2)
    ``move(rotate_deg, drive_m)``: turn in place by ``rotate_deg`` (positive: left,
    counter-clockwise), closed loop on the gyro to within 0.3 deg, then drive straight
    ahead, open loop, until the encoders have counted ``drive_m`` (slowing down over the last
    10 cm), and brake. Each phase has a time limit (4 s), so a blocked robot stops trying.

How the robot judges success (its own reading, never ground truth)
    It dead-reckons its path from the start of the behaviour: distance from the encoders,
    direction from the gyro. Success is the thesis's rule: the heading changed by the
    intended rotation within +-5 deg (a robot deflected by an obstacle fails) and the
    displacement is 65-75 cm. Wheel odometry is only as honest as the wheels' grip, so:

    * Traction control. While driving straight each wheel's torque is limited below what
      friction carries (6 x 0.35 N m / 6 cm = 35 N of push, while friction carries about
      0.7 x 25 kg x g = 170 N): a robot pushing against what it cannot move stalls and its
      encoders stop, instead of spinning its wheels and counting metres it never went. The
      same limit decides how steep a ramp it climbs (about 9.5 deg head-on) and how heavy
      a thing it shoves (about 7 kg on a floor of friction 0.5). Turning in place is
      skidding by nature, so the rotation may use more torque (``turn_torque``).
    * The chain. A wheel in the air (over a gap, at a ramp's toe) would spin freely and
      over-count; chained to its neighbours it turns as they do.
    * Slip check. During the drive the encoders' own heading change (skid-steer kinematics,
      right minus left over the track) must agree with the gyro's within 10 deg: a robot
      with one side stuck and the other spinning (high-centred on a ramp's edge, a side
      hanging in a gap) does not trust its encoders.
    * Tilt check. The IMU must read less than 25 deg of tilt at the end: more, and the robot
      has tipped into a gap, off an edge or over.

What ground truth is kept (for reports only)
    ``pose()`` is the body's true planar pose (x, y, yaw) and height; ``fell()`` whether
    its base ended more than 5 cm below the floor it started on (in a gap).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
import sapien

from afford.sim.objects import yaw_quaternion

__all__ = ["MobileRobotConfig", "MobileRobot", "Odometry", "Pose2D", "WHEELS"]

_AXLE_Y = np.array([math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)])  # joint x -> robot y

#: Wheel joint names, (axle 0 rear .. 2 front) x (left, right).
WHEELS = tuple(f"wheel-{side}-{i}" for i in range(3) for side in ("left", "right"))


@dataclass(frozen=True)
class MobileRobotConfig:
    """Geometry, strength and controller settings of the mobile robot (metres, kg, N m, s)."""

    length: float = 0.45
    """Body length (x)."""
    width: float = 0.33
    """Body width (y)."""
    clearance: float = 0.06
    """Height of the body's bottom above the floor: small bumps pass under it."""
    body_top: float = 0.40
    """Top of the main body box."""
    height: float = 0.47
    """Top of the scanner head: the robot's full height."""
    head: tuple[float, float] = (0.08, 0.14)
    """Scanner head (length, width), on top of the body at its front edge."""
    mass: float = 22.0
    """Body mass (KURT3D weighs about 22 kg)."""
    com_x: float = 0.0
    """Where the body's centre of mass lies ahead of its centre (negative: behind; a crane's
    counterweight)."""
    wheel_radius: float = 0.06
    wheel_mass: float = 0.5
    wheel_inertia: float = 0.01
    """About the axle, kg m^2, with the motor's inertia through the gearbox (a bare 0.5 kg wheel
    has 1e-3: so light a wheel against a stiff drive and friction makes PhysX's solver stall)."""
    axles: tuple[float, float, float] = (-0.13, 0.0, 0.13)
    """x of the rear, middle and front axle."""
    track: float = 0.21
    """Distance between the left and right wheel centres (the wheels' outer edges at the
    body's sides). A track much narrower than the wheelbase cannot turn in place: the
    skidding front and rear wheels resist more than all six can drive."""
    wheel_friction: float = 0.9
    """PhysX averages the two materials: 0.9 with the floor's 0.5 gives 0.7 (rubber on a floor)."""
    body_friction: float = 0.1
    """The body's shell is smooth: it slides along what it touches."""
    speed: float = 0.40
    """Driving speed, m/s."""
    turn_rate: float = 60.0
    """Largest turning rate the controller asks for, deg/s."""
    drive_torque: float = 0.35
    """Per wheel while driving straight (traction control: below what friction carries)."""
    turn_floor: float = 0.8
    """Slowest wheel speed (rad/s) the rotation asks for until the heading is reached."""
    turn_torque: float = 4.0
    """Per wheel while turning in place."""
    drive_damping: float = 40.0
    """Velocity-drive gain, N m per rad/s of wheel speed error."""
    chain_stiffness: float = 1.0e4
    """N m per rad of angle difference between chained wheels of a side (0: no chain)."""
    chain_damping: float = 100.0
    yaw_tolerance_deg: float = 0.3
    """The rotation ends when the gyro is this close to the target heading."""
    rotate_time: float = 4.0
    """Time limit of the rotation, s."""
    drive_time: float = 4.0
    """Time limit of the drive, s."""
    brake_time: float = 0.3
    """Standing still after the drive before the odometry is read, s."""
    heading_tolerance_deg: float = 5.0
    """Success: the heading changed by the intended rotation within this."""
    displacement_range: tuple[float, float] = (0.65, 0.75)
    """Success: the displacement lies in this range, m."""
    slip_tolerance_deg: float = 10.0
    """Success: during the drive the encoders' heading change agrees with the gyro's within this
    (10 deg: the two sides' wheels counted 3.7 cm apart more than the body turned)."""
    tilt_limit_deg: float = 25.0
    """Success: the body ends leaning less than this (more: it has tipped into a gap or off a ramp)."""
    fall_depth: float = 0.05
    """Ground truth: the robot has fallen if its base ends this far below the start."""

    @property
    def scanner_mount(self) -> tuple[float, float, float]:
        """The scanner's centre in the robot frame: just ahead of the head's front face."""
        return (self.length / 2 + 0.01, 0.0, (self.body_top + self.height) / 2)

    def body_boxes(self) -> list[tuple[tuple[float, float, float], tuple[float, float, float]]]:
        """The body's collision boxes as (centre, half size) in the robot frame."""
        main = ((0.0, 0.0, (self.clearance + self.body_top) / 2),
                (self.length / 2, self.width / 2, (self.body_top - self.clearance) / 2))
        hl, hw = self.head
        head = ((self.length / 2 - hl / 2, 0.0, (self.body_top + self.height) / 2),
                (hl / 2, hw / 2, (self.height - self.body_top) / 2))
        return [main, head]


@dataclass(frozen=True)
class Pose2D:
    """A planar pose in the world frame (metres, degrees) plus the base's height."""

    x: float
    y: float
    yaw: float
    z: float = 0.0

    def to_dict(self) -> dict:
        return {"x": self.x, "y": self.y, "yaw": self.yaw, "z": self.z}


@dataclass(frozen=True)
class Odometry:
    """What the robot measured of one behaviour with its own encoders and IMU."""

    rotate_deg: float
    """The intended rotation."""
    heading_change_deg: float
    """Gyro: heading at the end minus heading at the start."""
    displacement_m: float
    """Dead reckoning (encoders for distance, gyro for direction): start to end, straight line."""
    travelled_m: float
    """Encoders: the distance driven forward during the drive."""
    slip_deg: float
    """During the drive, the encoders' heading change (skid-steer kinematics) minus the gyro's:
    large when one side's wheels spin without taking the robot along."""
    tilt_deg: float
    """IMU: how far the body leans from level at the end."""
    time_s: float
    """Simulated time the behaviour took."""
    dx_m: float = 0.0
    dy_m: float = 0.0
    """Dead reckoning: the displacement's components in the frame the robot started in."""
    heading_tolerance_deg: float = 5.0
    displacement_range: tuple[float, float] = (0.65, 0.75)
    slip_tolerance_deg: float = 10.0
    tilt_limit_deg: float = 25.0

    @property
    def heading_error_deg(self) -> float:
        """How far the heading change missed the intended rotation."""
        return self.heading_change_deg - self.rotate_deg

    @property
    def success(self) -> bool:
        """The thesis's rule (heading within +-5 deg of the intended one, displacement 65-75 cm),
        read only when the robot can trust its encoders (no slip) and stands (not tipped)."""
        lo, hi = self.displacement_range
        return (abs(self.heading_error_deg) <= self.heading_tolerance_deg and lo <= self.displacement_m <= hi
                and abs(self.slip_deg) <= self.slip_tolerance_deg and self.tilt_deg <= self.tilt_limit_deg)

    def to_dict(self) -> dict:
        return {"rotate_deg": self.rotate_deg, "heading_change_deg": self.heading_change_deg,
                "displacement_m": self.displacement_m, "travelled_m": self.travelled_m,
                "slip_deg": self.slip_deg, "tilt_deg": self.tilt_deg, "time_s": self.time_s,
                "success": self.success}


class _Reckoner:
    """Dead reckoning from the encoders and the gyro, one physics step at a time."""

    def __init__(self, robot: "MobileRobot"):
        self.robot = robot
        self.q = robot.encoders()
        self.last = robot.gyro()
        self.yaw = 0.0        # unwrapped gyro heading change since the start
        self.x = self.y = 0.0
        self.s = 0.0          # encoder distance along the heading
        self.turn = 0.0       # encoder wheel-travel difference (right - left), metres
        self.t = 0.0

    def update(self, dt: float) -> None:
        rb = self.robot
        g = rb.gyro()
        self.yaw += _wrap(g - self.last)
        self.last = g
        q = rb.encoders()
        dl, dr = rb._side_travel(self.q, q)
        self.q = q
        r = rb.config.wheel_radius
        ds = r * (dl + dr) / 2
        self.s += ds
        self.turn += r * (dr - dl)
        self.x += ds * math.cos(self.yaw)
        self.y += ds * math.sin(self.yaw)
        self.t += dt


def _yaw_of(q: np.ndarray) -> float:
    """Heading (radians) of the body's forward axis projected on the floor."""
    w, x, y, z = q
    fx = 1 - 2 * (y * y + z * z)
    fy = 2 * (x * y + w * z)
    return math.atan2(fy, fx)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class MobileRobot:
    """The robot in one SAPIEN scene, standing at ``(x, y)`` heading ``yaw_deg``.

    ``move`` steps the scene itself; pass ``on_step`` to watch each step (the world uses it
    to notice contacts).
    """

    def __init__(self, scene: sapien.Scene, config: MobileRobotConfig = MobileRobotConfig(),
                 x: float = 0.0, y: float = 0.0, yaw_deg: float = 0.0, floor: float = 0.0):
        self.scene = scene
        self.config = c = config
        body_material = sapien.physx.PhysxMaterial(c.body_friction, c.body_friction, 0.0)
        wheel_material = sapien.physx.PhysxMaterial(c.wheel_friction, c.wheel_friction, 0.0)
        ab = scene.create_articulation_builder()
        base = ab.create_link_builder()
        base.set_name("base")
        for centre, half in c.body_boxes():
            base.add_box_collision(sapien.Pose(centre), half_size=half, material=body_material)
        # Mass and inertia of the body as a uniform main box (the head is light).
        (_, _, zc), (hx, hy, hz) = c.body_boxes()[0]
        inertia = c.mass / 3 * np.array([hy ** 2 + hz ** 2, hx ** 2 + hz ** 2, hx ** 2 + hy ** 2])
        base.set_mass_and_inertia(c.mass, sapien.Pose([c.com_x, 0.0, zc]), inertia)
        r = c.wheel_radius
        for name in WHEELS:
            side, i = name.split("-")[1], int(name.split("-")[2])
            wy = c.track / 2 if side == "left" else -c.track / 2
            w = ab.create_link_builder(base)
            w.set_name(name)
            w.set_joint_name(name)
            # A joint turns about its frame's x axis: rotate that frame onto the axle (y).
            w.set_joint_properties("revolute_unwrapped", limits=[[-np.inf, np.inf]],
                                   pose_in_parent=sapien.Pose([c.axles[i], wy, r], _AXLE_Y),
                                   pose_in_child=sapien.Pose(q=_AXLE_Y))
            w.add_sphere_collision(radius=r, material=wheel_material)
            w.set_mass_and_inertia(c.wheel_mass, sapien.Pose(), np.full(3, c.wheel_inertia))
        self._add_links(ab, base)
        self.articulation = ab.build(fix_root_link=False)
        self.articulation.set_name("mobile-robot")
        self.articulation.set_sleep_threshold(0.0)  # its drives act every step: never asleep
        self.articulation.set_root_pose(sapien.Pose([x, y, floor], yaw_quaternion(yaw_deg)))
        self.links = {link.name: link for link in self.articulation.get_links()}
        self.base = self.links["base"]
        by_name = {j.name: j for j in self.articulation.get_active_joints()}
        self.wheels = [by_name[n] for n in WHEELS]  # active-joint order is not builder order
        order = [j.name for j in self.articulation.get_active_joints()]
        self._qindex = np.array([order.index(n) for n in WHEELS])
        if c.chain_stiffness > 0:
            # Each side's wheels are chained together: PhysX fixed tendons hold the angle
            # differences of neighbouring wheels at zero.
            for side in ("left", "right"):
                links = [self.links[f"wheel-{side}-{i}"] for i in range(3)]
                for a, b in zip(links, links[1:]):
                    self.articulation.create_fixed_tendon([self.base, a, b], [0.0, -1.0, 1.0], [0.0, -1.0, 1.0],
                                                          stiffness=c.chain_stiffness, damping=c.chain_damping)
        self.start_z = float(floor)
        self._torque = math.nan
        self._targets = (math.nan, math.nan)
        self._set_drive(0.0, 0.0, c.drive_torque)

    def _add_links(self, builder, base) -> None:
        """Add more links to the body before it is built (a crane, an arm); none here."""

    # -- senses ---------------------------------------------------------------------------
    def gyro(self) -> float:
        """The heading the gyro reads, radians (wrapped)."""
        return _yaw_of(self.base.entity_pose.q.tolist())  # float64 arithmetic, not float32

    def encoders(self) -> list[float]:
        """Wheel angles (radians) in :data:`WHEELS` order."""
        return self.articulation.get_qpos()[self._qindex].tolist()

    # -- ground truth ---------------------------------------------------------------------
    def pose(self) -> Pose2D:
        """The body's true planar pose (for reports only)."""
        p = self.base.entity_pose
        return Pose2D(float(p.p[0]), float(p.p[1]), math.degrees(_yaw_of(np.asarray(p.q, dtype=float))), float(p.p[2]))

    def fell(self) -> bool:
        return float(self.base.entity_pose.p[2]) < self.start_z - self.config.fall_depth

    # -- motion ---------------------------------------------------------------------------
    def _set_drive(self, left: float, right: float, torque: float) -> None:
        """Wheel speed targets (rad/s) per side, each wheel's torque limited to ``torque``.
        Called every physics step: the joints are only told what changed."""
        if torque != self._torque:
            for j in self.wheels:
                j.set_drive_properties(stiffness=0.0, damping=self.config.drive_damping, force_limit=torque)
            self._torque = torque
        if (left, right) != self._targets:
            for j in self.wheels[0::2]:  # WHEELS alternates left, right
                j.set_drive_velocity_target(left)
            for j in self.wheels[1::2]:
                j.set_drive_velocity_target(right)
            self._targets = (left, right)

    def _side_travel(self, q0: list[float], q1: list[float]) -> tuple[float, float]:
        """Each side's wheel angle change (its chained wheels turn alike: their mean)."""
        # Plain floats: this runs every physics step, where numpy's per-call cost dominates.
        # Summed in numpy's order, so the result is the same to the bit.
        l0, r0, l1, r1, l2, r2 = q0
        m0, s0, m1, s1, m2, s2 = q1
        return ((m0 - l0) + (m1 - l1) + (m2 - l2)) / 3, ((s0 - r0) + (s1 - r1) + (s2 - r2)) / 3

    def tilt(self) -> float:
        """The IMU's tilt: degrees between the body's up axis and the vertical."""
        w, x, y, z = np.asarray(self.base.entity_pose.q, dtype=float)
        up_z = 1 - 2 * (x * x + y * y)
        return math.degrees(math.acos(max(-1.0, min(1.0, up_z))))

    def move(self, rotate_deg: float, drive_m: float = 0.70,
             on_step: Callable[[], None] | None = None) -> Odometry:
        """Turn in place by ``rotate_deg`` (left positive), then drive ``drive_m`` straight ahead.

        Returns the robot's own reading of what happened (:class:`Odometry`).
        """
        c = self.config
        dt = self.scene.timestep
        r = c.wheel_radius
        odo = _Reckoner(self)

        def step() -> None:
            self.scene.step()
            odo.update(dt)
            if on_step is not None:
                on_step()

        # Rotation: closed loop on the gyro. Skidding wheels turn the body only above a
        # dead band of wheel speed, so the command never drops below ``turn_floor`` until the
        # heading is within tolerance; then the wheels stop and the body comes to rest.
        target = math.radians(rotate_deg)
        tol = math.radians(c.yaw_tolerance_deg)
        top = math.radians(c.turn_rate) * c.track / 2 / r * 2.0  # skidding wheels turn faster than kinematics says
        gain = top / math.radians(15.0)                             # full speed beyond 15 deg of error
        prev = odo.yaw
        for _ in range(int(round(c.rotate_time / dt))):
            err = target - odo.yaw
            rate = (odo.yaw - prev) / dt
            prev = odo.yaw
            if abs(err) < tol:
                if abs(rate) < math.radians(0.5):
                    break
                w = 0.0
            else:
                w = math.copysign(min(top, max(c.turn_floor, gain * abs(err))), err)
            self._set_drive(-w, w, c.turn_torque)
            step()
        # Drive: open loop straight ahead, slowing down over the last 10 cm, then brake.
        s0, turn0, yaw0 = odo.s, odo.turn, odo.yaw
        for _ in range(int(round(c.drive_time / dt))):
            remaining = drive_m - (odo.s - s0)
            if remaining <= 0.0:
                break
            v = min(c.speed, max(0.05, 4.0 * remaining))
            self._set_drive(v / r, v / r, c.drive_torque)
            step()
        self._set_drive(0.0, 0.0, c.drive_torque)
        for _ in range(int(round(c.brake_time / dt))):
            step()
        encoder_turn = (odo.turn - turn0) / c.track
        return Odometry(
            rotate_deg=float(rotate_deg),
            heading_change_deg=math.degrees(odo.yaw),
            displacement_m=float(math.hypot(odo.x, odo.y)),
            travelled_m=float(odo.s - s0),
            slip_deg=math.degrees(encoder_turn - (odo.yaw - yaw0)),
            tilt_deg=self.tilt(),
            time_s=float(odo.t),
            dx_m=float(odo.x),
            dy_m=float(odo.y),
            heading_tolerance_deg=c.heading_tolerance_deg,
            displacement_range=c.displacement_range,
            slip_tolerance_deg=c.slip_tolerance_deg,
            tilt_limit_deg=c.tilt_limit_deg,
        )
