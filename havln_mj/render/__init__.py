"""Offscreen rendering (EGL, OSMesa fallback) and top-down maps."""
