"""Handing freed heap memory back to the operating system after a large transient build."""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import sys


@functools.cache
def _malloc_trim():
    """Glibc's ``malloc_trim``, or None where there is none."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
    except OSError:
        return None
    return getattr(libc, "malloc_trim", None)


def release_free_memory() -> None:
    """Returns the C heap's free pages to the system (glibc's ``malloc_trim``; else nothing).

    Compiling a world allocates tens of megabytes that are freed at once, but glibc keeps
    them mapped: without this, a process that renders reports them as resident for its life.
    """
    trim = _malloc_trim()
    if trim is not None:
        trim(0)
