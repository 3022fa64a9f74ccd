"""The one shared GL context of the process, on the backend chosen for it.

One GL context per process is a requirement of the architecture: every
:class:`~havln_mj.render.camera.Camera` in a process renders through the same context, each with its
own MuJoCo ``MjrContext`` (its own offscreen framebuffer, textures and display lists). The context
is the one sanctioned process-wide object of ``havln_mj``; it is reached only through
:func:`acquire` and :func:`release`, which keep a reference count: the first :func:`acquire` creates
the context, the last :func:`release` frees it.

The backend is chosen by :mod:`havln_mj.render.gl_backends` (``$MUJOCO_GL``, else EGL then
OSMesa, each probed before it is used).

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
import importlib
import os
import threading
import weakref
from collections.abc import Callable
from typing import Any

from havln_mj.errors import InvalidArgumentError, RenderingUnavailableError
from havln_mj.render.gl_backends import (
    BACKENDS,
    DEFAULT_ORDER,
    backend_order,
    platform_ok,
    probe,
)


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
        if not platform_ok(name, platform):
            continue  # Unusable in this process; backend_order explains why.
        reason = probe(name)
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
