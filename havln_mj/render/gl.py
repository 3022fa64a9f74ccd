"""OpenGL backend selection and the one shared GL context of the process.

One GL context per process is a requirement of the architecture: every
:class:`~havln_mj.render.camera.Camera` in a process renders through the same context, each with its
own MuJoCo ``MjrContext`` (its own offscreen framebuffer, textures and display lists). The context
is the one sanctioned process-wide object of ``havln_mj``; it is reached only through
:func:`acquire` and :func:`release`, which keep a reference count: the first :func:`acquire` creates
the context, the last :func:`release` frees it.

Backend choice (:func:`backend_order` holds the pure decision, testable without GL):

- ``$MUJOCO_GL`` set to ``egl``, ``osmesa`` or ``glfw`` (any case) forces that backend alone.
- Otherwise EGL is tried first (headless, hardware or Mesa llvmpipe), then OSMesa.
- EGL is probed through ``ctypes`` (library, device enumeration, display, context) *before*
  ``mujoco.egl`` is imported, because that import pins ``PYOPENGL_PLATFORM=egl`` and PyOpenGL
  cannot switch platforms later in the process. For the same reason an already-set
  ``$PYOPENGL_PLATFORM`` restricts the choice to the matching backend.

The size passed to the context hardly matters: MuJoCo renders into its own offscreen
framebuffer, sized by ``model.vis.global_.offwidth/offheight`` when each ``MjrContext`` is
made. EGL contexts here are surfaceless and ignore the size; OSMesa allocates a default
buffer of the first requested size that MuJoCo never draws into.

Use a context from one thread at a time; after ``fork`` a child must acquire its own (a
handle inherited from the parent raises on :meth:`GLHandle.make_current`).
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import ctypes.util
import importlib
import os
import sys
import threading
import weakref
from collections.abc import Callable, Collection, Mapping
from typing import Any

from havln_mj.errors import InvalidArgumentError, RenderingUnavailableError

BACKENDS: tuple[str, ...] = ("egl", "osmesa", "glfw")
"""Backends ``$MUJOCO_GL`` may name."""

DEFAULT_ORDER: tuple[str, ...] = ("egl", "osmesa")
"""Backends tried, in order, when ``$MUJOCO_GL`` is unset or empty."""

# The PyOpenGL platform each backend needs (None: PyOpenGL's default, e.g. GLX).
_PYOPENGL_PLATFORM: dict[str, str | None] = {"egl": "egl", "osmesa": "osmesa", "glfw": None}


def _platform_ok(backend: str, platform: str | None) -> bool:
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
        if not _platform_ok(name, platform):
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


# ---------------------------------------------------------------------------- probes

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


def _make_context(backend: str, width: int, height: int) -> Any:
    """Imports the mujoco GLContext class of ``backend`` and creates a context."""
    module = importlib.import_module(f"mujoco.{backend}")
    return module.GLContext(width, height)


def _create(width: int, height: int) -> tuple[str, Any]:
    """Chooses a backend, creates its context; returns (backend, context)."""
    mujoco_gl = os.environ.get("MUJOCO_GL")
    requested = (mujoco_gl or "").strip().lower()
    names = (requested,) if requested in BACKENDS else DEFAULT_ORDER
    platform = (os.environ.get("PYOPENGL_PLATFORM") or "").strip().lower() or None
    reasons: dict[str, str] = {}
    available = []
    for name in names:
        if not _platform_ok(name, platform):
            continue  # Unusable in this process; backend_order explains why.
        reason = _PROBES[name]()
        if reason is None:
            available.append(name)
        else:
            reasons[name] = reason
    order = backend_order(
        mujoco_gl,
        available,
        pyopengl_platform=os.environ.get("PYOPENGL_PLATFORM"),
        reasons=reasons,
    )
    failures: dict[str, str] = {}
    for name in order:
        try:
            return name, _make_context(name, width, height)
        except Exception as exc:  # Backends raise ImportError, RuntimeError, GLError, ...
            failures[name] = f"{type(exc).__name__}: {exc}"
    # Every probed backend failed when actually created; report that through the same path.
    backend_order(mujoco_gl, (), reasons={**reasons, **failures})
    raise AssertionError("unreachable")  # pragma: no cover


# ------------------------------------------------------------------- shared context


class GLSession:
    """The process's one GL context with its reference count. Created only by :func:`acquire`.

    Attributes:
        backend: ``"egl"``, ``"osmesa"`` or ``"glfw"``.
        context: The ``mujoco.<backend>.GLContext`` object.
        refcount: Number of unreleased handles.
        pid: Process that created the context.
    """

    def __init__(self, backend: str, context: Any) -> None:
        self.backend = backend
        self.context = context
        self.refcount = 0
        self.pid = os.getpid()
        self._handles: weakref.WeakSet[GLHandle] = weakref.WeakSet()

    @property
    def closed(self) -> bool:
        """Whether the context has been freed."""
        return self.context is None

    def make_current(self) -> None:
        """Makes the context current on the calling thread.

        Raises:
            RenderingUnavailableError: If the context was freed, or was made in another
                process (inherited through ``fork``).
        """
        if self.context is None:
            raise RenderingUnavailableError("the shared GL context has been freed")
        if self.pid != os.getpid():
            raise RenderingUnavailableError(
                "the shared GL context was created in a parent process; create renderers "
                "after fork (or use the 'spawn' start method)"
            )
        self.context.make_current()

    def _free(self) -> None:
        if self.context is not None and self.pid == os.getpid():
            self.context.free()
        self.context = None

    def __repr__(self) -> str:
        state = "closed" if self.closed else f"refcount={self.refcount}"
        return f"GLSession(backend={self.backend!r}, {state})"


class GLHandle:
    """One claim on the shared :class:`GLSession`; release it once (extra releases are no-ops)."""

    def __init__(self, session: GLSession, on_exit: Callable[[], None] | None) -> None:
        self.session = session
        self._released = False
        self._on_exit = weakref.WeakMethod(on_exit) if _is_bound(on_exit) else on_exit

    @property
    def released(self) -> bool:
        """Whether this handle has been released."""
        return self._released

    @property
    def backend(self) -> str:
        """The backend of the shared context."""
        return self.session.backend

    def make_current(self) -> None:
        """Makes the shared context current on the calling thread.

        Raises:
            RenderingUnavailableError: If this handle was released or the context is unusable.
        """
        if self._released:
            raise RenderingUnavailableError("this GL handle has been released")
        self.session.make_current()

    def release(self) -> None:
        """Releases this handle; see :func:`release`."""
        release(self)

    def _exit_callback(self) -> Callable[[], None] | None:
        cb = self._on_exit
        return cb() if isinstance(cb, weakref.WeakMethod) else cb


def _is_bound(fn: Any) -> bool:
    return fn is not None and hasattr(fn, "__self__") and hasattr(fn, "__func__")


_LOCK = threading.RLock()
_SESSION: GLSession | None = None
_ATEXIT_REGISTERED = False


def acquire(
    max_width: int = 640, max_height: int = 480, on_exit: Callable[[], None] | None = None
) -> GLHandle:
    """Returns a handle on the shared GL context, creating it on first use.

    Args:
        max_width: Width the context is created with if it does not exist yet.
        max_height: Height the context is created with if it does not exist yet.
        on_exit: Called at interpreter exit, before the context is freed, if the handle is
            still held (e.g. a renderer's ``close`` to free its ``MjrContext``). Bound
            methods are held weakly.

    Returns:
        A :class:`GLHandle`; pass it to :func:`release` when done.

    Raises:
        InvalidArgumentError: If a size is not a positive int.
        RenderingUnavailableError: If no OpenGL backend can be started.
    """
    global _SESSION, _ATEXIT_REGISTERED
    for label, value in (("max_width", max_width), ("max_height", max_height)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise InvalidArgumentError(f"{label} must be a positive int, got {value!r}")
    with _LOCK:
        if _SESSION is not None and (_SESSION.closed or _SESSION.pid != os.getpid()):
            _SESSION = None  # Inherited through fork: never touch the parent's context.
        if _SESSION is None:
            backend, context = _create(max_width, max_height)
            _SESSION = GLSession(backend, context)
            if not _ATEXIT_REGISTERED:
                # Registered after mujoco.<backend> is imported, so it runs before that
                # module's own exit hooks (e.g. EGL display termination).
                atexit.register(_shutdown)
                _ATEXIT_REGISTERED = True
        handle = GLHandle(_SESSION, on_exit)
        _SESSION.refcount += 1
        _SESSION._handles.add(handle)
        return handle


def release(handle: GLHandle) -> None:
    """Releases ``handle``; frees the shared context when it was the last one. Idempotent."""
    global _SESSION
    with _LOCK:
        if handle._released:
            return
        handle._released = True
        session = handle.session
        session._handles.discard(handle)
        session.refcount -= 1
        if session.refcount <= 0:
            session._free()
            if _SESSION is session:
                _SESSION = None


def active_session() -> GLSession | None:
    """Returns the live shared session of this process, or None if no handle is held."""
    with _LOCK:
        if _SESSION is None or _SESSION.closed or _SESSION.pid != os.getpid():
            return None
        return _SESSION


def _shutdown() -> None:
    """At exit: lets holders free their GL objects, then frees the context."""
    session = active_session()
    if session is None:
        return
    for handle in list(session._handles):
        callback = handle._exit_callback()
        if callback is not None:
            with contextlib.suppress(Exception):  # Best effort at interpreter exit.
                callback()
        release(handle)
    with _LOCK:
        if not session.closed:
            session._free()
