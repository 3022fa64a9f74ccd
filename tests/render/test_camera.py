"""Tests of the offscreen RGB-D Camera and the shared GL context (EGL, small images)."""

from __future__ import annotations

import gc
import math

import mujoco
import numpy as np
import pytest

from havln_mj.errors import InvalidArgumentError, RenderingUnavailableError
from havln_mj.frames import camera_quat
from havln_mj.render import gl
from havln_mj.render.camera import FAR_M, Camera, Frame

W, H = 64, 48
EYE = 1.5  # Camera height in metres.
T = 0.05  # Half-thickness of walls.
RED = (1.0, 0.0, 0.0, 1.0)
GREY = (0.5, 0.5, 0.5, 1.0)


def make_world(
    boxes=(),
    *,
    heading: float = 0.0,
    elevation: float = 0.0,
    floor: bool = False,
    offsize: int = 16,
):
    """Returns (model, data): boxes (half-size, pos, rgba[, group]) and a posed camera."""
    spec = mujoco.MjSpec()
    spec.visual.global_.offwidth = offsize
    spec.visual.global_.offheight = offsize
    world = spec.worldbody
    if floor:
        world.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[50, 50, 0.1], rgba=GREY)
    for box in boxes:
        size, pos, rgba, *group = box
        geom = world.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=size, pos=pos, rgba=rgba)
        if group:
            geom.group = group[0]
    world.add_light(pos=[0, 0, 6], dir=[0, 0, -1])
    body = world.add_body(name="agent", mocap=True, pos=[0, 0, EYE])
    body.add_camera(name="agent_cam")
    body.add_camera(name="other_cam")
    model = spec.compile()
    data = mujoco.MjData(model)
    pose(model, data, heading, elevation)
    return model, data


def pose(model, data, heading: float, elevation: float = 0.0) -> None:
    data.mocap_quat[0] = camera_quat(heading, elevation)
    mujoco.mj_forward(model, data)


def wall_ahead_y(dist: float, half_x: float = 40.0, half_z: float = 40.0, rgba=RED):
    """A wall whose near face is the plane y = dist, centred on the camera axis."""
    return ([half_x, T, half_z], [0.0, dist + T, EYE], rgba)


def wall_ahead_x(dist: float, rgba=RED):
    """A wall whose near face is the plane x = dist."""
    return ([T, 40.0, 40.0], [dist + T, 0.0, EYE], rgba)


@pytest.fixture
def cameras():
    """Collects cameras made in a test and closes them afterwards."""
    made: list[Camera] = []

    def make(*args, **kwargs) -> Camera:
        cam = Camera(*args, **kwargs)
        made.append(cam)
        return cam

    yield make
    for cam in made:
        cam.close()


# ------------------------------------------------------------------------ images


def test_shapes_dtypes_and_fresh_arrays(cameras):
    model, data = make_world([wall_ahead_y(3.0)])
    cam = cameras(model, width=W, height=H)
    first = cam.render(data)
    second = cam.render(data)
    assert isinstance(first, Frame)
    assert first.rgb.shape == (H, W, 3) and first.rgb.dtype == np.uint8
    assert first.depth.shape == (H, W) and first.depth.dtype == np.float32
    assert first.rgb.flags.c_contiguous and first.depth.flags.c_contiguous
    assert not np.shares_memory(first.rgb, second.rgb)
    assert not np.shares_memory(first.depth, second.depth)
    np.testing.assert_array_equal(first.depth, second.depth)


def test_enlarges_offscreen_buffer(cameras):
    model, _ = make_world([wall_ahead_y(3.0)], offsize=16)
    cameras(model, width=100, height=70)
    assert model.vis.global_.offwidth >= 100
    assert model.vis.global_.offheight >= 70


@pytest.mark.parametrize("dist", [1.0, 3.0, 7.0])
def test_depth_to_wall_straight_ahead(cameras, dist):
    model, data = make_world([wall_ahead_y(dist)])
    depth = cameras(model, width=W, height=H).render(data, rgb=False).depth
    assert depth[H // 2, W // 2] == pytest.approx(dist, abs=0.02)
    # Planar z-depth: the whole wall reads the same distance, corners included.
    np.testing.assert_allclose(depth, dist, atol=0.02)


@pytest.mark.parametrize("dist", [1.0, 3.0, 7.0])
def test_heading_convention_wall_along_plus_x(cameras, dist):
    model, data = make_world([wall_ahead_x(dist)], heading=math.pi / 2)
    cam = cameras(model, width=W, height=H)
    depth = cam.render(data).depth
    np.testing.assert_allclose(depth, dist, atol=0.02)
    # Facing +y instead (heading 0), the +x wall is off to the right, not ahead.
    pose(model, data, 0.0)
    depth = cam.render(data).depth
    assert depth[H // 2, W // 2] == 0.0
    assert depth[H // 2, -1] > 0.0 and depth[H // 2, 0] == 0.0


def test_elevation_convention_looks_down_at_floor(cameras):
    model, data = make_world(floor=True, elevation=-math.radians(30))
    depth = cameras(model, width=W, height=H).render(data).depth
    # The centre ray meets the floor after EYE / sin(30°) = 3 m along the optical axis.
    centre = depth[H // 2 - 1 : H // 2 + 1, W // 2 - 1 : W // 2 + 1].mean()
    assert centre == pytest.approx(2 * EYE, abs=0.02)
    # Top rows look farther than bottom rows.
    assert depth[H // 4, W // 2] > depth[-1, W // 2] > 0.0


def test_depth_is_planar_not_euclidean(cameras):
    dist = 3.0
    model, data = make_world([wall_ahead_y(dist)])
    cam = cameras(model, width=W, height=H, vfov_deg=90.0)
    depth = cam.render(data).depth
    corner_ray = dist * math.hypot(1.0, math.tan(math.radians(cam.hfov) / 2), 1.0)
    assert corner_ray > dist + 1.0  # A Euclidean depth would differ a lot at the corners.
    for r, c in [(0, 0), (0, W - 1), (H - 1, 0), (H - 1, W - 1), (H // 2, W // 2)]:
        assert depth[r, c] == pytest.approx(dist, abs=0.02)


def test_nothing_hit_reads_zero(cameras):
    model, data = make_world([wall_ahead_y(3.0, half_x=0.5, half_z=0.5)])
    depth = cameras(model, width=W, height=H).render(data).depth
    assert depth[0, 0] == 0.0 and depth[-1, -1] == 0.0
    assert depth[H // 2, W // 2] == pytest.approx(3.0, abs=0.02)


def test_beyond_far_plane_reads_zero(cameras):
    model, data = make_world([wall_ahead_y(FAR_M + 20.0, half_x=200, half_z=200)])
    depth = cameras(model, width=W, height=H).render(data).depth
    assert np.all(depth == 0.0)


def test_red_wall_renders_red(cameras):
    model, data = make_world([wall_ahead_y(3.0)])
    rgb = cameras(model, width=W, height=H).render(data).rgb
    r, g, b = (int(v) for v in rgb[H // 2, W // 2])
    assert r > 60 and r > 2 * g and r > 2 * b


def test_top_row_first(cameras):
    # Red above the eye, green below: row 0 must be red.
    green = (0.0, 1.0, 0.0, 1.0)
    model, data = make_world(
        [
            ([40, T, 20], [0, 3 + T, EYE + 20], RED),
            ([40, T, 20], [0, 3 + T, EYE - 20], green),
        ]
    )
    rgb = cameras(model, width=W, height=H).render(data).rgb
    assert rgb[0, W // 2, 0] > rgb[0, W // 2, 1]
    assert rgb[-1, W // 2, 1] > rgb[-1, W // 2, 0]


def _hit_rows_cols(depth: np.ndarray) -> tuple[int, int]:
    return int(np.count_nonzero(depth[:, W // 2] > 0)), int(np.count_nonzero(depth[H // 2] > 0))


def test_vfov_sets_apparent_size(cameras):
    dist, half = 4.0, 1.0  # A 2 m × 2 m panel 4 m ahead, nothing behind it.
    model, data = make_world([wall_ahead_y(dist, half_x=half, half_z=half)])
    cam = cameras(model, width=W, height=H, vfov_deg=60.0)
    for vfov in (60.0, 90.0, 40.0):
        cam.set_vfov(vfov)
        assert cam.vfov == vfov
        rows, cols = _hit_rows_cols(cam.render(data).depth)
        tan_v = math.tan(math.radians(vfov) / 2)
        tan_h = tan_v * W / H  # Horizontal FOV follows the aspect ratio.
        assert math.tan(math.radians(cam.hfov) / 2) == pytest.approx(tan_h)
        assert rows == pytest.approx(H * (half / dist) / tan_v, abs=1.5)
        assert cols == pytest.approx(W * (half / dist) / tan_h, abs=1.5)


def test_two_cameras_on_one_model_camera_keep_their_vfov(cameras):
    model, data = make_world([wall_ahead_y(4.0, half_x=1.0, half_z=1.0)])
    narrow = cameras(model, width=W, height=H, vfov_deg=40.0)
    wide = cameras(model, width=W, height=H, vfov_deg=90.0)
    rows_narrow, _ = _hit_rows_cols(narrow.render(data).depth)
    rows_wide, _ = _hit_rows_cols(wide.render(data).depth)
    assert rows_narrow > rows_wide
    assert _hit_rows_cols(narrow.render(data).depth)[0] == rows_narrow


def test_rgb_only_and_depth_only_match_rgbd(cameras):
    model, data = make_world([wall_ahead_y(3.0, half_x=1.0)], floor=True)
    cam = cameras(model, width=W, height=H)
    both = cam.render(data)
    rgb_only = cam.render(data, depth=False)
    depth_only = cam.render(data, rgb=False)
    assert rgb_only.depth is None and depth_only.rgb is None
    np.testing.assert_array_equal(rgb_only.rgb, both.rgb)
    np.testing.assert_array_equal(depth_only.depth, both.depth)


def test_geom_groups(cameras):
    hidden = ([40, T, 40], [0, 2 + T, EYE], RED, 3)  # Group 3: not drawn by default.
    model, data = make_world([hidden, wall_ahead_y(5.0)])
    default = cameras(model, width=W, height=H).render(data).depth
    assert default[H // 2, W // 2] == pytest.approx(5.0, abs=0.02)
    with_3 = cameras(model, width=W, height=H, geom_groups=[0, 3]).render(data).depth
    assert with_3[H // 2, W // 2] == pytest.approx(2.0, abs=0.02)
    only_3 = cameras(model, width=W, height=H, geom_groups=(3,)).render(data).depth
    assert only_3[H // 2, W // 2] == pytest.approx(2.0, abs=0.02)
    none = cameras(model, width=W, height=H, geom_groups=[]).render(data).depth
    assert np.all(none == 0.0)


def test_other_named_camera_and_properties(cameras):
    model, data = make_world([wall_ahead_y(3.0)])
    cam = cameras(model, "other_cam", width=32, height=24, vfov_deg=45.0)
    assert (cam.width, cam.height, cam.vfov) == (32, 24, 45.0)
    assert cam.camera_name == "other_cam"
    assert cam.camera_id == mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "other_cam")
    assert cam.render(data).depth[12, 16] == pytest.approx(3.0, abs=0.02)
    assert "other_cam" in repr(cam)


# ------------------------------------------------------------------- GL session


def test_cameras_share_one_gl_context_and_free_it():
    model, data = make_world([wall_ahead_y(3.0)])
    before = gl.active_session()
    base = before.refcount if before is not None else 0
    first = Camera(model, width=W, height=H)
    second = Camera(model, "other_cam", width=32, height=32)
    session = first.gl_session
    assert session is not None and session is second.gl_session
    assert gl.active_session() is session
    assert session.refcount == base + 2
    assert session.backend in gl.BACKENDS
    first.close()
    first.close()  # Idempotent.
    assert first.closed and first.gl_session is None
    assert session.refcount == base + 1 and not session.closed
    assert second.render(data).depth[16, 16] == pytest.approx(3.0, abs=0.02)
    second.close()
    if before is None:
        assert session.closed and gl.active_session() is None
        # A later camera starts a fresh context.
        with Camera(model, width=W, height=H) as third:
            assert third.gl_session is not session
            assert third.render(data).depth[H // 2, W // 2] == pytest.approx(3.0, abs=0.02)
        assert gl.active_session() is None


def test_context_manager_and_del_release():
    model, _ = make_world([wall_ahead_y(3.0)])
    before = gl.active_session()
    base = before.refcount if before is not None else 0
    with Camera(model, width=W, height=H) as cam:
        assert cam.gl_session.refcount == base + 1
    assert cam.closed
    cam = Camera(model, width=W, height=H)
    session = cam.gl_session
    del cam
    gc.collect()
    assert session.refcount == base


def test_render_after_close_raises():
    model, data = make_world([wall_ahead_y(3.0)])
    cam = Camera(model, width=W, height=H)
    cam.close()
    with pytest.raises(RuntimeError, match="closed"):
        cam.render(data)


def test_acquire_release_handles():
    before = gl.active_session()
    base = before.refcount if before is not None else 0
    a = gl.acquire(8, 8)
    b = gl.acquire(16, 16)
    assert a.session is b.session and a.session.refcount == base + 2
    a.make_current()
    gl.release(a)
    gl.release(a)  # Idempotent per handle.
    assert b.session.refcount == base + 1 and a.released
    with pytest.raises(RenderingUnavailableError):
        a.make_current()
    b.release()
    if before is None:
        assert b.session.closed and gl.active_session() is None
    with pytest.raises(InvalidArgumentError):
        gl.acquire(0, 8)


# -------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "kwargs",
    [
        {"width": 0},
        {"width": -1},
        {"width": 1.5},
        {"width": True},
        {"height": 9000},
        {"height": "48"},
        {"vfov_deg": 0.0},
        {"vfov_deg": 180.0},
        {"vfov_deg": float("nan")},
        {"vfov_deg": "60"},
        {"geom_groups": [7]},
        {"geom_groups": [-1]},
        {"geom_groups": 3},
        {"msaa_samples": -1},
    ],
)
def test_bad_arguments(kwargs):
    model, _ = make_world()
    with pytest.raises(InvalidArgumentError):
        Camera(model, **{"width": W, "height": H, **kwargs})


def test_unknown_camera_lists_valid_names():
    model, _ = make_world()
    with pytest.raises(InvalidArgumentError, match="agent_cam") as info:
        Camera(model, "agent_camera", width=W, height=H)
    assert "other_cam" in str(info.value) and "agent_camera" in str(info.value)
    assert isinstance(info.value, ValueError)


def test_bad_model_and_orthographic_camera():
    with pytest.raises(InvalidArgumentError):
        Camera("not a model", width=W, height=H)  # type: ignore[arg-type]
    model, _ = make_world()
    model.cam_projection[0] = mujoco.mjtProjection.mjPROJ_ORTHOGRAPHIC
    with pytest.raises(InvalidArgumentError, match="orthographic"):
        Camera(model, width=W, height=H)


def test_bad_render_and_set_vfov_arguments(cameras):
    model, data = make_world()
    cam = cameras(model, width=W, height=H)
    with pytest.raises(InvalidArgumentError):
        cam.render(data, rgb=False, depth=False)
    with pytest.raises(InvalidArgumentError):
        cam.set_vfov(-5.0)
    assert cam.vfov == 60.0


def test_failed_construction_holds_no_gl_reference():
    before = gl.active_session()
    model, _ = make_world()
    with pytest.raises(InvalidArgumentError):
        Camera(model, "nope", width=W, height=H)
    assert gl.active_session() is before


# ------------------------------------------------------------ backend decision


def test_backend_order_default_prefers_egl():
    assert gl.backend_order(None, {"egl", "osmesa"}) == ["egl", "osmesa"]
    assert gl.backend_order("", ["egl"]) == ["egl"]


def test_backend_order_egl_missing_falls_back_to_osmesa():
    assert gl.backend_order(None, {"osmesa"}) == ["osmesa"]


@pytest.mark.parametrize(
    ("value", "expected"), [("egl", "egl"), ("OSMesa", "osmesa"), (" GLFW ", "glfw")]
)
def test_backend_order_env_override(value, expected):
    assert gl.backend_order(value, set(gl.BACKENDS)) == [expected]


def test_backend_order_forced_backend_unavailable():
    with pytest.raises(RenderingUnavailableError, match="egl") as info:
        gl.backend_order("egl", {"osmesa"}, reasons={"egl": "libEGL cannot be loaded"})
    message = str(info.value)
    assert "libEGL cannot be loaded" in message and "libegl1" in message
    assert "osmesa" not in message.split("To fix")[0]


def test_backend_order_nothing_available_says_what_to_do():
    with pytest.raises(RenderingUnavailableError) as info:
        gl.backend_order(None, set(), reasons={"egl": "no EGL devices found"})
    message = str(info.value)
    for part in ("egl", "osmesa", "no EGL devices found", "libosmesa6", "libegl1", "MUJOCO_GL"):
        assert part in message
    assert isinstance(info.value, RuntimeError)


def test_backend_order_invalid_env_value():
    with pytest.raises(RenderingUnavailableError, match="vulkan") as info:
        gl.backend_order("vulkan", {"egl"})
    assert "osmesa" in str(info.value)


def test_backend_order_respects_pinned_pyopengl_platform():
    both = {"egl", "osmesa"}
    assert gl.backend_order(None, both, pyopengl_platform="egl") == ["egl"]
    assert gl.backend_order(None, both, pyopengl_platform="osmesa") == ["osmesa"]
    with pytest.raises(RenderingUnavailableError, match="PYOPENGL_PLATFORM"):
        gl.backend_order("osmesa", both, pyopengl_platform="egl")
    assert gl.backend_order("glfw", set(gl.BACKENDS), pyopengl_platform="glx") == ["glfw"]
    with pytest.raises(RenderingUnavailableError, match="PYOPENGL_PLATFORM"):
        gl.backend_order("glfw", set(gl.BACKENDS), pyopengl_platform="egl")
