"""Floor plans: rooms tile the footprint, doors sit on shared walls and join every room."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from havln_mj.scene.procedural.layout import plan_house
from havln_mj.scene.procedural.recipe import load_recipe


@pytest.mark.parametrize("seed", range(25))
def test_plan_invariants(seed):
    recipe = load_recipe()
    plan = plan_house(np.random.default_rng(seed), recipe)
    rooms = plan.rooms
    assert sum(r.area for r in rooms) == pytest.approx(plan.width * plan.depth, rel=1e-6)
    for i, r in enumerate(rooms):
        assert r.x1 - r.x0 >= 1.25 and r.y1 - r.y0 >= 1.25
        for s in rooms[i + 1 :]:
            overlap_x = min(r.x1, s.x1) - max(r.x0, s.x0)
            overlap_y = min(r.y1, s.y1) - max(r.y0, s.y0)
            assert overlap_x <= 1e-6 or overlap_y <= 1e-6  # no two rooms overlap
    for d in plan.doors:
        a, b = rooms[d.a], rooms[d.b]
        assert d.width >= recipe["door_width"][0] - 1e-6
        for r in (a, b):
            lo, hi = (r.y0, r.y1) if d.vertical else (r.x0, r.x1)
            edges = (r.x0, r.x1) if d.vertical else (r.y0, r.y1)
            assert lo - 1e-6 <= d.lo and d.hi <= hi + 1e-6
            assert min(abs(d.coord - e) for e in edges) < 1e-6  # on the room's wall line
    n = len(rooms)
    adj = csr_matrix(
        (np.ones(len(plan.doors)), ([d.a for d in plan.doors], [d.b for d in plan.doors])),
        shape=(n, n),
    )
    assert connected_components(adj, directed=False)[0] == 1


def test_plans_cover_the_size_range():
    recipe = load_recipe()
    areas = [(p := plan_house(np.random.default_rng(s), recipe)).width * p.depth for s in range(40)]
    assert min(areas) < 70 and max(areas) > 200
    assert all(40 <= a <= 250 for a in areas)
