"""What a procedural house's seed produces, before it is written as a scan folder."""

from __future__ import annotations

from dataclasses import dataclass

from havln_mj.scene.boxes import BoxSet
from havln_mj.scene.connectivity import Connectivity
from havln_mj.scene.procedural.furnish import Item
from havln_mj.scene.procedural.layout import FloorPlan
from havln_mj.scene.procedural.recipe import Recipe
from havln_mj.scene.procedural.viewpoints import ViewpointGraph
from havln_mj.scene.regions import Regions


@dataclass(frozen=True)
class ProceduralHouse:
    """Everything a seed produces, before it is written to disk."""

    scene_id: str
    seed: int
    plan: FloorPlan
    items: tuple[Item, ...]
    boxes: BoxSet
    viewpoints: ViewpointGraph
    connectivity: Connectivity
    regions: Regions
    recipe: Recipe

    @property
    def recipe_digest(self) -> str:
        """The digest of the recipe the house was drawn from."""
        return self.recipe.digest

    @property
    def area(self) -> float:
        """Floor area in m²."""
        return self.plan.width * self.plan.depth
