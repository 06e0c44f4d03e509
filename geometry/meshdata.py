"""The mesh handed from ``geometry`` to ``solver``: a DOLFINx mesh with named tags."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only: no dolfinx import at run time
    from dolfinx.mesh import Mesh, MeshTags


@dataclass(frozen=True)
class MeshData:
    """A distributed DOLFINx mesh and its tags, as every builder in ``geometry`` returns it.

    Attributes:
        mesh: ``dolfinx.mesh.Mesh`` (ghost mode ``shared_facet`` so interface integrals work).
        cell_tags: ``dolfinx.mesh.MeshTags`` of dimension tdim: one tag per cell.
        facet_tags: ``dolfinx.mesh.MeshTags`` of dimension tdim - 1 (boundaries, interfaces).
        cell_names: physical-group name -> cell tag value (e.g. ``"soil_layer_03"``, ``"pile_1"``,
            ``"cap"``).
        facet_names: physical-group name -> facet tag value (e.g. ``"bottom"``,
            ``"ground_surface"``, ``"shaft_p1_l03"``).
        info: free-form provenance (sizes, timings, cache key) for summaries.
    """

    mesh: Mesh
    cell_tags: MeshTags
    facet_tags: MeshTags
    cell_names: dict[str, int]
    facet_names: dict[str, int]
    info: dict[str, Any] = field(default_factory=dict)

    def cell_tag(self, name: str) -> int:
        """Tag value of the cell group ``name`` (KeyError lists the known names)."""
        try:
            return self.cell_names[name]
        except KeyError:
            raise KeyError(f"no cell group {name!r}; known: {sorted(self.cell_names)}") from None

    def facet_tag(self, name: str) -> int:
        """Tag value of the facet group ``name`` (KeyError lists the known names)."""
        try:
            return self.facet_names[name]
        except KeyError:
            raise KeyError(f"no facet group {name!r}; known: {sorted(self.facet_names)}") from None
