"""``havln_mj view``: the live MuJoCo viewer on a scene, with keyboard control of the agent.

Opens ``mujoco.viewer`` on the world of a simulator's element: the building, the people going
about their activities in simulated time (the clock runs at real time between actions: the
agent waits), the agent (the point body's camera rig, or the GO1) and the navigation graph
drawn over the scene (viewpoints as spheres, edges as lines; the agent's viewpoint in
orange). Keys:

===============  ================================================================
Up arrow         FORWARD (point body: to the navigable viewpoint ahead; GO1: 0.5 m)
Left / Right     turn left / right (30°; GO1 45°)
Page Up / Down   look up / down (point body)
Space            wait one second
===============  ================================================================

It needs a display (GLFW); under a headless machine use Xvfb (``xvfb-run havln_mj view``).
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import mujoco
import numpy as np

from havln_mj import argchecks
from havln_mj.errors import HavlnError, InvalidArgumentError
from havln_mj.frames import heading_to
from havln_mj.render.camera import FAR_M, NEAR_M
from havln_mj.robot.point_body import CAMERA
from havln_mj.sim.egocentric import EgoAction
from havln_mj.sim.legged import CHASE_CAMERA

_GLFW = {"up": 265, "left": 263, "right": 262, "page_up": 266, "page_down": 267, "space": 32}
EGO_KEYS = {
    _GLFW["up"]: EgoAction.FORWARD,
    _GLFW["left"]: EgoAction.TURN_LEFT,
    _GLFW["right"]: EgoAction.TURN_RIGHT,
    _GLFW["page_up"]: EgoAction.LOOK_UP,
    _GLFW["page_down"]: EgoAction.LOOK_DOWN,
}
ROBOT_KEYS = {_GLFW["up"]: "forward", _GLFW["left"]: "turn_left", _GLFW["right"]: "turn_right"}
WAIT_KEY = _GLFW["space"]


def draw_graph(scene: mujoco.MjvScene, graph, here: str) -> None:
    """Draws the navigation graph into a viewer's user scene (replacing what was there)."""
    scene.ngeom = 0
    nodes = graph.nodes
    edges = graph.edges()
    if len(nodes) + len(edges) > scene.maxgeom:
        nodes, edges = nodes[: scene.maxgeom // 2], edges[: scene.maxgeom // 2]
    eye = np.eye(3).ravel()
    for vp in nodes:
        g = scene.geoms[scene.ngeom]
        rgba = np.array([1.0, 0.5, 0.0, 0.9] if vp == here else [0.1, 0.6, 1.0, 0.6], np.float32)
        pos = graph.position(vp).copy()
        pos[2] = graph.floor_z(vp) + 0.05
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_SPHERE, np.full(3, 0.12), pos, eye, rgba)
        scene.ngeom += 1
    for a, b, _ in edges:
        g = scene.geoms[scene.ngeom]
        pa, pb = graph.position(a).copy(), graph.position(b).copy()
        pa[2], pb[2] = graph.floor_z(a) + 0.05, graph.floor_z(b) + 0.05
        mujoco.mjv_initGeom(
            g, mujoco.mjtGeom.mjGEOM_LINE, np.zeros(3), np.zeros(3), eye,
            np.array([0.1, 0.6, 1.0, 0.5], np.float32),
        )  # fmt: skip
        mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_LINE, 2.0, pa, pb)
        scene.ngeom += 1


def watch(cam: mujoco.MjvCamera, model: mujoco.MjModel) -> None:
    """Shows the scene through the robot's chase camera if there is one, else the agent's own.

    (Esc in the viewer switches to the free camera.)
    """
    names = {model.camera(i).name for i in range(model.ncam)}
    cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
    cam.fixedcamid = model.camera(CHASE_CAMERA if CHASE_CAMERA in names else CAMERA).id


class LiveView:
    """Steps a simulator from key presses and keeps a viewer's model and data in sync.

    Args:
        sim: An initialised simulator with a started episode (batch size 1).
        scene: The scan id.
    """

    def __init__(self, sim, scene: str) -> None:
        self.sim, self.scene = sim, scene
        self.graph = sim.graph(scene)
        self.keys: list[int] = []
        self.robot = bool(sim.robot_actions)

    def key(self, keycode: int) -> None:
        """The viewer's key callback: queues the key (acted on in the loop)."""
        self.keys.append(int(keycode))

    def act(self, seconds: float) -> None:
        """Takes the queued actions, else lets ``seconds`` of simulated time pass."""
        if not self.keys:
            self.sim.wait([seconds])
            return
        keycode = self.keys.pop(0)
        if keycode == WAIT_KEY:
            self.sim.wait([1.0])
        elif self.robot and keycode in ROBOT_KEYS:
            self.sim.makeRobotAction([ROBOT_KEYS[keycode]])
        elif not self.robot and keycode in EGO_KEYS:
            self.sim.makeEgoAction([EGO_KEYS[keycode]])

    def sync(self, viewer) -> None:
        """Poses the world at the element's time and shows it with the graph."""
        self.sim.draw(0)  # the viewer shows the very model and data drawn into
        state = self.sim.getState()[0]
        with viewer.lock():
            draw_graph(viewer.user_scn, self.graph, state.location.viewpointId)
        viewer.sync()


def run_viewer(
    scene: str,
    *,
    body: str = "point",
    humans: bool = True,
    seed: int = 0,
    frames: int | None = None,
    keys: Sequence[int] = (),
    launch: Callable | None = None,
    human_placements: str | Path | None = None,
    mp3d_dir: str | Path | None = None,
    connectivity_dir: str | Path | None = None,
) -> int:
    """Opens the live viewer; returns the number of frames shown.

    Args:
        scene: Scene id.
        body: ``"point"`` or ``"go1"``.
        humans: Whether the scene has people.
        seed: Seed of the people and the start.
        frames: Stop after this many frames (None: until the window closes).
        keys: GLFW key codes to press before any typed ones (scripted sessions, tests).
        launch: The viewer launcher (default ``mujoco.viewer.launch_passive``).
        human_placements: HA3D placement file for real scans (default
            ``$HAVLN_HA3D_PLACEMENTS``; without one, people are placed by HA3D's rule).
        mp3d_dir: Matterport3D data root (default ``$HAVLN_MP3D_DIR``).
        connectivity_dir: Folder of connectivity graphs (default ``$HAVLN_CONNECTIVITY_DIR``).
    """
    from havln_mj.sim.simulator import Simulator

    if frames is not None and (
        isinstance(frames, bool) or not isinstance(frames, int) or frames < 1
    ):
        raise InvalidArgumentError(f"frames must be None or an int ≥ 1, got {frames!r}")
    sim = Simulator(humans=humans, body=body, human_placements=human_placements)
    if mp3d_dir is not None:
        sim.setDatasetPath(mp3d_dir)
    if connectivity_dir is not None:
        sim.setNavGraphPath(connectivity_dir)
    sim.setRenderingEnabled(False)
    sim.setRestrictedNavigation(False)
    sim.setSeed(seed)
    sim.initialize()
    graph = sim.graph(scene)
    start = graph.nodes[int(np.random.default_rng(seed).integers(graph.num_nodes))]
    ahead = graph.neighbors(start)
    heading = heading_to(graph.position(start), graph.position(ahead[0])) if ahead else 0.0
    sim.newEpisode([scene], [start], [heading], [0.0])  # facing along an edge
    live = LiveView(sim, scene)
    live.keys.extend(int(k) for k in keys)
    if launch is None:
        import mujoco.viewer

        launch = mujoco.viewer.launch_passive
    model, data = sim.draw(0)
    # The clipping planes scale with the model's extent, which parked people inflate.
    extent = float(model.stat.extent) or 1.0
    model.vis.map.znear, model.vis.map.zfar = NEAR_M / extent, FAR_M / extent
    shown, period = 0, 1.0 / 30.0
    before = set(threading.enumerate())
    with launch(
        model, data, key_callback=live.key, show_left_ui=False, show_right_ui=False
    ) as viewer:
        with viewer.lock():
            watch(viewer.cam, model)
        while viewer.is_running() and (frames is None or shown < frames):
            t0 = time.perf_counter()
            live.act(period)
            live.sync(viewer)
            shown += 1
            time.sleep(max(0.0, period - (time.perf_counter() - t0)))
        viewer.close()
    # The viewer renders on threads of its own: let them finish tearing down before GLFW
    # terminates at exit (else it crashes mid-teardown).
    for thread in set(threading.enumerate()) - before:
        thread.join(timeout=5.0)
    sim.close()
    return shown


def parser(prog: str = "havln_mj view") -> argparse.ArgumentParser:
    """The command's argument parser."""
    p = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    p.add_argument("--scene", default="proc-0", help="scene id (default proc-0)")
    p.add_argument(
        "--body", choices=("point", "go1"), default="point", help="agent body (default point)"
    )
    p.add_argument("--no-people", action="store_true", help="leave the scene empty")
    p.add_argument("--seed", type=int, default=0, help="seed of the people and the start")
    p.add_argument("--frames", type=int, default=None, help="close after this many frames")
    p.add_argument(
        "--keys",
        default="",
        help="comma-separated keys to press first: up, left, right, page_up, page_down, space",
    )
    argchecks.add_data_flags(p, "--human-placements", "--mp3d-dir", "--connectivity-dir")
    return p


def _problems(args: argparse.Namespace) -> list[str | None]:
    keys = [k.strip() for k in args.keys.split(",") if k.strip()]
    unknown = [k for k in keys if k not in _GLFW]
    headless = sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    )
    return [
        f"--keys {unknown!r} unknown; valid: {', '.join(_GLFW)}" if unknown else None,
        argchecks.in_range("--seed", args.seed, 0),
        None if args.frames is None else argchecks.in_range("--frames", args.frames, 1),
        argchecks.scene_ids("--scene", [args.scene]),
        argchecks.existing("--human-placements", args.human_placements, "file"),
        argchecks.existing("--mp3d-dir", args.mp3d_dir),
        argchecks.existing("--connectivity-dir", args.connectivity_dir),
        "the viewer needs a display: $DISPLAY is not set (on a headless machine run it under "
        "a virtual one: xvfb-run havln_mj view ...)"
        if headless
        else None,
    ]


def main(argv: Sequence[str] | None = None, prog: str = "havln_mj view") -> int:
    """Runs the viewer; returns the exit code (2 on bad input)."""
    args = parser(prog).parse_args(argv)
    problems = [p for p in _problems(args) if p]
    if problems:
        print(f"error: {problems[0]}", file=sys.stderr)
        return 2
    keys = [k.strip() for k in args.keys.split(",") if k.strip()]
    try:
        shown = run_viewer(
            args.scene,
            body=args.body,
            humans=not args.no_people,
            seed=args.seed,
            frames=args.frames,
            keys=[_GLFW[k] for k in keys],
            human_placements=args.human_placements,
            mp3d_dir=args.mp3d_dir,
            connectivity_dir=args.connectivity_dir,
        )
    except HavlnError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"viewer closed after {shown} frames")
    return 0
