"""Navigability of a compiled world: per-level occupancy grids and geodesics on them."""

from havln_mj.nav.grid import NavGrid, build_navgrids
from havln_mj.nav.spec import LEGGED_BAND, PERSON_BAND, GridSpec

__all__ = ["LEGGED_BAND", "PERSON_BAND", "GridSpec", "NavGrid", "build_navgrids"]
