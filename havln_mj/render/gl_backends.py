"""Which OpenGL backend to use: the pure choice, and probes that test a backend without GL.

:func:`backend_order` holds the pure decision, testable without GL;
:mod:`havln_mj.render.gl` creates the shared context on the first backend it returns that starts.

- ``$MUJOCO_GL`` set to ``egl``, ``osmesa`` or ``glfw`` (any case) forces that backend alone.
- Otherwise EGL is tried first (headless, hardware or Mesa llvmpipe), then OSMesa.
- EGL is probed through ``ctypes`` (library, device enumeration, display, context) *before*
  ``mujoco.egl`` is imported, because that import pins ``PYOPENGL_PLATFORM=egl`` and PyOpenGL
  cannot switch platforms later in the process. For the same reason an already-set
  ``$PYOPENGL_PLATFORM`` restricts the choice to the matching backend.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import importlib
import os
import sys
from collections.abc import Callable, Collection, Mapping

from havln_mj.errors import RenderingUnavailableError

BACKENDS: tuple[str, ...] = ("egl", "osmesa", "glfw")
"""Backends ``$MUJOCO_GL`` may name."""

DEFAULT_ORDER: tuple[str, ...] = ("egl", "osmesa")
"""Backends tried, in order, when ``$MUJOCO_GL`` is unset or empty."""

# The PyOpenGL platform each backend needs (None: PyOpenGL's default, e.g. GLX).
_PYOPENGL_PLATFORM: dict[str, str | None] = {"egl": "egl", "osmesa": "osmesa", "glfw": None}


def platform_ok(backend: str, platform: str | None) -> bool:
    """Whether ``backend`` can run once PyOpenGL is pinned to ``platform`` (None: unpinned)."""
    needed = _PYOPENGL_PLATFORM[backend]
    if platform is None:
        return True
    if needed is None:
        return platform not in ("egl", "osmesa")
    return platform == needed


_FIXES: dict[str, str] = {
    "egl": "install EGL and Mesa drivers (apt-get install libegl1 libgl1-mesa-dri), "
    "or an NVIDIA driver with EGL support",
    "osmesa": "install OSMesa (apt-get install libosmesa6)",
    "glfw": "run under a display server (set $DISPLAY) with glfw installed (pip install glfw)",
}


def backend_order(
    mujoco_gl: str | None,
    available: Collection[str],
    *,
    pyopengl_platform: str | None = None,
    reasons: Mapping[str, str] | None = None,
) -> list[str]:
    """Returns the backends to try, best first. Pure: no GL, no environment access.

    Args:
        mujoco_gl: The value of ``$MUJOCO_GL`` (None or empty: choose automatically).
        available: Backends whose libraries could be loaded and probed.
        pyopengl_platform: The value of ``$PYOPENGL_PLATFORM``; once set, only the backend
            using that PyOpenGL platform can work in this process.
        reasons: Why each unavailable backend failed its probe, quoted in the error.

    Returns:
        A non-empty list of backend names from :data:`BACKENDS`.

    Raises:
        RenderingUnavailableError: If ``mujoco_gl`` names no known backend, or no candidate
            backend is available; the message says what was tried and how to fix it.
    """
    reasons = reasons or {}
    requested = (mujoco_gl or "").strip().lower()
    if requested:
        if requested not in BACKENDS:
            raise RenderingUnavailableError(
                f"MUJOCO_GL={mujoco_gl!r} is not a backend havln_mj can use; "
                f"set it to one of {', '.join(BACKENDS)} or unset it to choose automatically."
            )
        candidates: tuple[str, ...] = (requested,)
    else:
        candidates = DEFAULT_ORDER

    platform = (pyopengl_platform or "").strip().lower() or None
    notes: dict[str, str] = {}
    result = []
    for name in candidates:
        if not platform_ok(name, platform):
            needed = _PYOPENGL_PLATFORM[name]
            notes[name] = (
                f"PYOPENGL_PLATFORM={pyopengl_platform!r} is already set in this process "
                f"({name} needs {needed or 'the default platform'})"
            )
        elif name not in available:
            notes[name] = reasons.get(name, "not available")
        else:
            result.append(name)
    if result:
        return result

    how = "; ".join(f"{name}: {notes[name]}" for name in candidates)
    fixes = "; or ".join(_FIXES[name] for name in candidates)
    hint = "" if requested else " Or set MUJOCO_GL to a backend that works on this machine."
    raise RenderingUnavailableError(
        f"No OpenGL backend could be started (tried {', '.join(candidates)}: {how}). "
        f"To fix: {fixes}.{hint}"
    )


_EGL_PLATFORM_DEVICE_EXT = 0x313F
_EGL_SUCCESS_TRUE = 1
_EGL_CONFIG_ATTRIBS = (
    0x3024, 8,  # EGL_RED_SIZE
    0x3023, 8,  # EGL_GREEN_SIZE
    0x3022, 8,  # EGL_BLUE_SIZE
    0x3021, 8,  # EGL_ALPHA_SIZE
    0x3025, 24,  # EGL_DEPTH_SIZE
    0x3033, 0x0001,  # EGL_SURFACE_TYPE: EGL_PBUFFER_BIT
    0x3040, 0x0008,  # EGL_RENDERABLE_TYPE: EGL_OPENGL_BIT
    0x3038,  # EGL_NONE
)  # fmt: skip
_EGL_OPENGL_API = 0x30A2


def _probe_egl() -> str | None:
    """Returns None if an EGL device context can be created, else why not (ctypes only)."""
    if "mujoco.egl" in sys.modules:
        return None  # Already imported (e.g. by `import mujoco` under MUJOCO_GL=egl).
    name = ctypes.util.find_library("EGL") or "libEGL.so.1"
    try:
        lib = ctypes.CDLL(name)
    except OSError as exc:
        return f"libEGL cannot be loaded ({exc})"
    vp = ctypes.c_void_p
    lib.eglGetProcAddress.restype = vp
    lib.eglGetProcAddress.argtypes = [ctypes.c_char_p]
    query_addr = lib.eglGetProcAddress(b"eglQueryDevicesEXT")
    display_addr = lib.eglGetProcAddress(b"eglGetPlatformDisplayEXT")
    if not query_addr or not display_addr:
        return "libEGL lacks EGL_EXT_device_enumeration / EGL_EXT_platform_device"
    query_devices = ctypes.CFUNCTYPE(
        ctypes.c_uint, ctypes.c_int, ctypes.POINTER(vp), ctypes.POINTER(ctypes.c_int)
    )(query_addr)
    get_display = ctypes.CFUNCTYPE(vp, ctypes.c_uint, vp, vp)(display_addr)
    lib.eglInitialize.argtypes = [vp, vp, vp]
    lib.eglChooseConfig.argtypes = [vp, ctypes.POINTER(ctypes.c_int), vp, ctypes.c_int, vp]
    lib.eglBindAPI.argtypes = [ctypes.c_uint]
    lib.eglCreateContext.restype = vp
    lib.eglCreateContext.argtypes = [vp, vp, vp, vp]
    lib.eglDestroyContext.argtypes = [vp, vp]

    devices = (vp * 16)()
    count = ctypes.c_int(0)
    if query_devices(16, devices, ctypes.byref(count)) != _EGL_SUCCESS_TRUE or not count.value:
        return "no EGL devices found"
    attribs = (ctypes.c_int * len(_EGL_CONFIG_ATTRIBS))(*_EGL_CONFIG_ATTRIBS)
    for i in range(count.value):
        # The display is left initialised: mujoco.egl gets the same one and re-initialises it.
        display = get_display(_EGL_PLATFORM_DEVICE_EXT, devices[i], None)
        if not display or lib.eglInitialize(display, None, None) != _EGL_SUCCESS_TRUE:
            continue
        config = vp()
        num = ctypes.c_int(0)
        ok = lib.eglChooseConfig(display, attribs, ctypes.byref(config), 1, ctypes.byref(num))
        if ok != _EGL_SUCCESS_TRUE or num.value < 1:
            continue
        if lib.eglBindAPI(_EGL_OPENGL_API) != _EGL_SUCCESS_TRUE:
            continue
        context = lib.eglCreateContext(display, config, None, None)
        if context:
            lib.eglDestroyContext(display, context)
            return None
    return f"none of {count.value} EGL device(s) could create an OpenGL context"


def _probe_osmesa() -> str | None:
    """Returns None if libOSMesa can be loaded, else why not."""
    if "mujoco.osmesa" in sys.modules:
        return None
    names = [ctypes.util.find_library("OSMesa"), "libOSMesa.so.8", "libOSMesa.so"]
    for name in filter(None, names):
        try:
            ctypes.CDLL(name)
        except OSError:
            continue
        return None
    return "libOSMesa not found"


def _probe_glfw() -> str | None:
    """Returns None if glfw is importable and a display server is named, else why not."""
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return "no $DISPLAY"
    try:
        importlib.import_module("glfw")
    except Exception as exc:  # glfw raises ImportError or its own errors without a library.
        return f"glfw cannot be imported ({exc})"
    return None


_PROBES: dict[str, Callable[[], str | None]] = {
    "egl": _probe_egl,
    "osmesa": _probe_osmesa,
    "glfw": _probe_glfw,
}


def probe(backend: str) -> str | None:
    """Returns None if ``backend`` looks usable in this process, else why not."""
    return _PROBES[backend]()
