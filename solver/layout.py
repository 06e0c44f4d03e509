"""Bodies and the block layout of the coupled problem: spaces, sub-meshes, dof and facet maps.

A *body* is one displacement field: the whole mesh when the piles are tied to the soil, or the
soil and the structure (piles and cap) on their own sub-meshes of the one conforming parent mesh
(``dolfinx.mesh.create_submesh``), joined only by the interface terms. The excess pore pressure
lives on the soil cells only (a sub-mesh when there are solids).

Block order of the monolithic system: ``[u (soil, or the whole mesh), p, u_structure]``.
Roles: ``"all"`` (tied), ``"soil"``, ``"structure"``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import basix.ufl
import numpy as np
import ufl
from dolfinx import common, fem, la
from dolfinx import mesh as dmesh
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
from petsc4py import PETSc

from pilegroup.errors import SolverInputError
from pilegroup.geometry import groups
from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver.inputs import Discretisation, ElasticSolid, SoilMaterial
from pilegroup.solver.qpstate import QuadratureState

SQRT2 = float(np.sqrt(2.0))
Material = SoilMaterial | ElasticSolid


def eps_mandel(u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Mandel strain 6-vector ``(xx, yy, zz, sqrt2 xy, sqrt2 xz, sqrt2 yz)`` of ``u`` (UFL)."""
    e = ufl.sym(ufl.grad(u))
    return ufl.as_vector(
        [e[0, 0], e[1, 1], e[2, 2], SQRT2 * e[0, 1], SQRT2 * e[0, 2], SQRT2 * e[1, 2]]
    )


@dataclass(frozen=True)
class BodySplit:
    """Structure (piles + cap) and soil as sub-meshes of one parent mesh.

    ``is_structure[c]`` tells for every local parent cell (owned and ghost) whether it belongs to
    the structure; ``soil_layer[c]`` is the 0-based layer index of soil cells (-1 elsewhere).
    """

    parent: dmesh.Mesh
    structure: dmesh.Mesh
    structure_map: dmesh.EntityMap
    soil: dmesh.Mesh
    soil_map: dmesh.EntityMap
    soil_vertex_map: dmesh.EntityMap
    is_structure: np.ndarray
    soil_layer: np.ndarray
    n_layers: int


def split_bodies(md: MeshData) -> BodySplit:
    """Split ``md`` into structure and soil sub-meshes by cell group (:mod:`geometry.groups`).

    Soil groups are the soil layers (``groups.layer_of``), structure groups the piles and the
    cap (``groups.is_structure``); every cell must carry a tag.
    """
    msh = md.mesh
    tdim = msh.topology.dim
    imap = msh.topology.index_map(tdim)
    n_local = imap.size_local + imap.num_ghosts
    is_structure = np.zeros(n_local, dtype=bool)
    soil_layer = np.full(n_local, -1, dtype=np.int32)
    tagged = np.zeros(n_local, dtype=bool)
    layer_ids = []
    for name, value in md.cell_names.items():
        cells = md.cell_tags.find(value)
        tagged[cells] = True
        layer = groups.layer_of(name)
        if groups.is_structure(name):
            is_structure[cells] = True
        elif layer is not None:
            soil_layer[cells] = layer - 1
            layer_ids.append(layer - 1)
        else:
            raise ValueError(f"cell group {name!r} is neither structure nor a soil layer")
    if not tagged.all():
        raise ValueError(f"{int((~tagged).sum())} cells carry no cell tag")
    n_layers = msh.comm.allreduce(max(layer_ids, default=-1) + 1, op=MPI.MAX)
    struct_cells = np.flatnonzero(is_structure).astype(np.int32)
    soil_cells = np.flatnonzero(~is_structure).astype(np.int32)
    structure, structure_map, _, _ = dmesh.create_submesh(msh, tdim, struct_cells)
    soil, soil_map, soil_vmap, _ = dmesh.create_submesh(msh, tdim, soil_cells)
    return BodySplit(msh, structure, structure_map, soil, soil_map, soil_vmap, is_structure,
                     soil_layer, n_layers)


@dataclass
class Body:
    """One displacement field with its quadrature-point state.

    Attributes:
        name: role, ``"all"`` (tied), ``"soil"`` or ``"structure"``.
        mesh: the body's mesh (the parent mesh for ``"all"``).
        emap: entity map sub-mesh -> parent (``None`` for the parent mesh itself).
        tags: parent cell tags of the body.
        V: displacement space; u, u_n: current and committed displacement (m).
        qp: stress and tangent at the quadrature points.
    """

    name: str
    mesh: dmesh.Mesh
    emap: dmesh.EntityMap | None
    tags: tuple[int, ...]
    V: fem.FunctionSpace
    u: fem.Function
    u_n: fem.Function
    qp: QuadratureState


class BlockLayout:
    """Bodies, the pressure space and the block structure of the unknowns.

    Args:
        md: mesh and tags.
        materials: cell-group name -> material; every owned cell must be covered.
        disc: element pair and quadrature degree.
        separate: give the structure its own field (interface coupling) instead of tying it.
    """

    def __init__(self, md: MeshData, materials: Mapping[str, Material], disc: Discretisation,
                 separate: bool) -> None:
        self.md, self.mesh, self.comm = md, md.mesh, md.mesh.comm
        self.materials = dict(materials)
        soil_cells = self._check_coverage()
        self.soil_tags = tuple(md.cell_tag(n) for n, m in self.materials.items()
                               if isinstance(m, SoilMaterial))
        self.solid_tags = tuple(md.cell_tag(n) for n, m in self.materials.items()
                                if not isinstance(m, SoilMaterial))
        self.has_solids = len(self.solid_tags) > 0
        if separate and not (self.has_solids and self.soil_tags):
            raise SolverInputError("interface coupling needs both solid and soil cell groups")
        tdim = self.mesh.topology.dim
        self.mesh.topology.create_connectivity(tdim - 1, tdim)
        self.split: BodySplit | None = None
        self.emaps: list[dmesh.EntityMap] | None
        if not separate:
            specs = [("all", self.mesh, None, self.soil_tags + self.solid_tags)]
            if self.has_solids:
                self.p_mesh, p_emap, self.p_vertex_map, _ = dmesh.create_submesh(
                    self.mesh, tdim, soil_cells)
                self.emaps = [p_emap]
            else:
                self.p_mesh, self.p_vertex_map, self.emaps = self.mesh, None, None
        else:
            self.split = split = split_bodies(md)
            specs = [("soil", split.soil, split.soil_map, self.soil_tags),
                     ("structure", split.structure, split.structure_map, self.solid_tags)]
            self.p_mesh, self.p_vertex_map = split.soil, split.soil_vertex_map
            self.emaps = [split.soil_map, split.structure_map]
        self.bodies = [self._make_body(disc, *spec) for spec in specs]
        Qe = basix.ufl.element("Lagrange", self.mesh.basix_cell(), 1)
        self.Q = fem.functionspace(self.p_mesh, Qe)
        self.p = fem.Function(self.Q, name="excess_pore_pressure")
        self.p_n = fem.Function(self.Q)
        self.fields = [self.bodies[0].u, self.p] + [b.u for b in self.bodies[1:]]
        self.fields_n = [self.bodies[0].u_n, self.p_n] + [b.u_n for b in self.bodies[1:]]
        self.u_blocks = [0] + list(range(2, len(self.fields)))

    def _check_coverage(self) -> np.ndarray:
        """Materials must cover every owned cell; returns the soil cells (local, sorted)."""
        md, tdim = self.md, self.mesh.topology.dim
        imap = self.mesh.topology.index_map(tdim)
        n_owned = imap.size_local
        covered = np.zeros(n_owned + imap.num_ghosts, dtype=bool)
        soil = [np.zeros(0, np.int32)]
        for name, mat in self.materials.items():
            if not isinstance(mat, SoilMaterial | ElasticSolid):
                raise SolverInputError(
                    f"materials[{name!r}] = {type(mat).__name__}; allowed: SoilMaterial, "
                    "ElasticSolid")
            cells = md.cell_tags.find(md.cell_tag(name))
            if isinstance(mat, SoilMaterial):
                soil.append(cells)
            covered[cells] = True
        if not covered[:n_owned].all():
            raise SolverInputError(
                f"materials cover {int(covered[:n_owned].sum())} of {n_owned} owned cells; "
                f"cell groups: {sorted(md.cell_names)}")
        return np.unique(np.concatenate(soil)).astype(np.int32)

    def _make_body(self, disc: Discretisation, name: str, mesh: dmesh.Mesh,
                   emap: dmesh.EntityMap | None, tags: tuple[int, ...]) -> Body:
        Ve = basix.ufl.element("Lagrange", self.mesh.basix_cell(), disc.u_degree, shape=(3,))
        V = fem.functionspace(mesh, Ve)
        u = fem.Function(V, name="displacement" if name == "all" else f"displacement_{name}")
        u_n = fem.Function(V)
        n_owned = self.mesh.topology.index_map(self.mesh.topology.dim).size_local
        cell_groups = {}
        for gname, mat in self.materials.items():
            if self.md.cell_tag(gname) not in tags:
                continue
            cells = self.md.cell_tags.find(self.md.cell_tag(gname))
            cells = cells[cells < n_owned]
            if emap is not None:
                cells = emap.sub_topology_to_topology(cells, inverse=True).astype(np.int32)
            cell_groups[gname] = (mat, cells)
        qp = QuadratureState(mesh, cell_groups, disc.quadrature_degree,
                             eps_mandel(u) - eps_mandel(u_n))
        return Body(name, mesh, emap, tags, V, u, u_n, qp)

    # ------------------------------------------------------------------ roles and blocks
    def body(self, role: str) -> Body:
        """The body with role ``role`` (the whole mesh, ``"all"``, when the piles are tied)."""
        for b in self.bodies:
            if b.name == role or b.name == "all":
                return b
        raise KeyError(f"no body {role!r}; bodies: {[b.name for b in self.bodies]}")

    def block_of(self, body: Body) -> int:
        """Block index of a body's displacement (0 for the first body, 2, 3, ... after p)."""
        i = self.bodies.index(body)
        return 0 if i == 0 else i + 1

    @property
    def num_dofs(self) -> int:
        """Global number of unknowns (u and p)."""
        return int(sum(b.V.dofmap.index_map.size_global * 3 for b in self.bodies)
                   + self.Q.dofmap.index_map.size_global)

    # ------------------------------------------------------------------ facets and dofs
    def facets(self, name: str) -> np.ndarray:
        """Local parent facets of facet group ``name``."""
        return self.md.facet_tags.find(self.md.facet_tag(name))

    def _facet_counts(self, name: str) -> np.ndarray:
        """Number of facets of group ``name`` on each body's cells (all ranks; collective)."""
        tdim = self.mesh.topology.dim
        f2c = self.mesh.topology.connectivity(tdim - 1, tdim)
        cells = np.array([f2c.links(f)[0] for f in self.facets(name)], dtype=np.int32)
        counts = np.array([int(np.sum(self.split.is_structure[cells]
                                      == (b.name == "structure"))) for b in self.bodies])
        return self.comm.allreduce(counts, op=MPI.SUM)

    def body_of_facet(self, name: str) -> Body:
        """The body whose cells carry (most of) the facet group ``name`` (collective)."""
        if len(self.bodies) == 1:
            return self.bodies[0]
        return self.bodies[int(np.argmax(self._facet_counts(name)))]

    def bodies_of_facet(self, name: str) -> list[Body]:
        """Every body with facets in group ``name`` (e.g. a symmetry plane cuts both)."""
        if len(self.bodies) == 1:
            return list(self.bodies)
        return [b for b, n in zip(self.bodies, self._facet_counts(name), strict=True) if n > 0]

    def sub_facets(self, body: Body, facets: np.ndarray) -> np.ndarray:
        """Parent facets -> facets of ``body``'s sub-mesh (through an adjacent body cell).

        ``create_submesh`` keeps each cell's vertex order, so a facet has the same local index
        in the parent cell and in its sub-mesh copy.
        """
        if body.emap is None:
            return facets
        tdim = self.mesh.topology.dim
        self.mesh.topology.create_connectivity(tdim, tdim - 1)
        body.mesh.topology.create_connectivity(tdim, tdim - 1)
        body.mesh.topology.create_connectivity(tdim - 1, tdim)
        f2c = self.mesh.topology.connectivity(tdim - 1, tdim)
        c2f = self.mesh.topology.connectivity(tdim, tdim - 1)
        sc2f = body.mesh.topology.connectivity(tdim, tdim - 1)
        out = []
        for k in range(2):  # each facet has one or two cells; take one inside the body
            has = (f2c.offsets[facets + 1] - f2c.offsets[facets]) > k
            f = facets[has]
            c = f2c.array[f2c.offsets[f] + k]
            sc = body.emap.sub_topology_to_topology(c.astype(np.int32), inverse=True)
            inside = sc >= 0
            for fi, ci, si in zip(f[inside], c[inside], sc[inside], strict=True):
                lf = int(np.flatnonzero(c2f.links(ci) == fi)[0])
                out.append(sc2f.links(si)[lf])
        return np.unique(np.array(out, dtype=np.int32))

    def facet_dofs(self, body: Body, name: str, component: int) -> np.ndarray:
        """Dofs of ``component`` of ``body``'s displacement on the parent facet group ``name``."""
        fdim = self.mesh.topology.dim - 1
        facets = self.sub_facets(body, self.facets(name))
        return fem.locate_dofs_topological(body.V.sub(component), fdim, facets)

    def pressure_dofs(self, name: str | None) -> np.ndarray:
        """Pressure dofs on facet group ``name`` (all local dofs for ``None``)."""
        if name is None:
            qmap = self.Q.dofmap.index_map
            return np.arange(qmap.size_local + qmap.num_ghosts, dtype=np.int32)
        facets = self.facets(name)
        fdim = self.mesh.topology.dim - 1
        if not self.has_solids:
            return fem.locate_dofs_topological(self.Q, fdim, facets)
        self.mesh.topology.create_connectivity(fdim, 0)
        f2v = self.mesh.topology.connectivity(fdim, 0)
        pv = np.unique(np.concatenate([f2v.links(f) for f in facets])) if len(facets) \
            else np.zeros(0, dtype=np.int32)
        sv = self.p_vertex_map.sub_topology_to_topology(pv.astype(np.int32), inverse=True)
        sv = sv[sv >= 0].astype(np.int32)
        self.p_mesh.topology.create_connectivity(0, self.p_mesh.topology.dim)
        return fem.locate_dofs_topological(self.Q, 0, sv)

    def pressure_dofs_in_cells(self, name: str) -> np.ndarray:
        """Every pressure dof of the soil cell group ``name`` (a drained layer)."""
        md = self.md
        cells = md.cell_tags.find(md.cell_tag(name)).astype(np.int32)
        if self.has_solids:  # parent cells -> the pressure's sub-mesh
            cells = self.emaps[0].sub_topology_to_topology(cells, inverse=True)  # type: ignore[index]
            cells = cells[cells >= 0].astype(np.int32)
        tdim = self.p_mesh.topology.dim
        self.p_mesh.topology.create_connectivity(tdim, tdim)
        return fem.locate_dofs_topological(self.Q, tdim, cells)

    # ------------------------------------------------------------------ vectors
    def commit_fields(self) -> None:
        """Current fields become the committed ones (``u_n``, ``p_n``)."""
        for f, fn in zip(self.fields, self.fields_n, strict=True):
            fn.x.array[:] = f.x.array

    def restore_fields(self) -> None:
        """Current fields return to the committed ones."""
        for f, fn in zip(self.fields, self.fields_n, strict=True):
            f.x.array[:] = fn.x.array

    def fields_to_x(self, x: PETSc.Vec) -> None:
        """Copy the current fields into the block vector ``x``."""
        fpetsc.assign(self.fields, x)

    def x_to_fields(self, x: PETSc.Vec) -> None:
        """Copy the block vector ``x`` (ghosts updated) into the fields."""
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        fpetsc.assign(x, self.fields)

    def block_norms(self, vec: PETSc.Vec) -> np.ndarray:
        """Euclidean norm of every block of ``vec`` (all ranks)."""
        off0, _ = vec.getAttr("_blocks")
        a = vec.array_r
        loc = np.array([float(a[off0[i]:off0[i + 1]] @ a[off0[i]:off0[i + 1]])
                        for i in range(len(self.fields))])
        return np.sqrt(self.comm.allreduce(loc, op=MPI.SUM))

    # ------------------------------------------------------------------ solver splits
    def _block_offsets(self, A: PETSc.Mat) -> np.ndarray:
        """Global first row of every block's owned rows in ``A`` (and the end of the last)."""
        sizes = [f.function_space.dofmap.index_map.size_local
                 * f.function_space.dofmap.index_map_bs for f in self.fields]
        return A.getOwnershipRange()[0] + np.concatenate([[0], np.cumsum(sizes)])

    def index_sets(self, A: PETSc.Mat) -> tuple[PETSc.IS, PETSc.IS]:
        """Displacement and pressure index sets of the monolithic matrix ``A``."""
        offs = self._block_offsets(A)
        u_rows = np.concatenate([np.arange(offs[i], offs[i + 1]) for i in self.u_blocks])
        is_p = PETSc.IS().createStride(int(offs[2] - offs[1]), first=int(offs[1]), step=1,
                                       comm=self.comm)
        return self._rows_is(u_rows), is_p

    def splits(self, A: PETSc.Mat, names: tuple[str, ...], band_layers: int = 0
               ) -> list[tuple[str, PETSc.IS, PETSc.NullSpace | None]]:
        """Index sets of the field-split blocks ``names`` of ``A`` (``presets.Preset.splits``).

        ``"u"`` (every displacement, with the rigid-body modes), ``"p"`` (pressure),
        ``"structure"`` and ``"soil"`` (:meth:`interface_index_sets` with ``band_layers``; the
        soil with its modes); each as ``(name, index set, near-nullspace or None)``
        (collective).
        """
        known = ("u", "p", "structure", "soil")
        if any(n not in known for n in names):
            raise SolverInputError(f"field-split blocks {names}; allowed: {known}")
        is_u, is_p = self.index_sets(A)
        sets: dict[str, tuple[PETSc.IS, PETSc.NullSpace | None]] = {"p": (is_p, None)}
        if "u" in names:
            sets["u"] = (is_u, self.rigid_body_modes())
        if "structure" in names or "soil" in names:
            is_t, is_s, nns = self.interface_index_sets(A, band_layers)
            sets["structure"], sets["soil"] = (is_t, None), (is_s, nns)
        return [(n, *sets[n]) for n in names]

    def interface_soil_nodes(self) -> np.ndarray:
        """Owned soil displacement nodes on the pile–soil interface (local numbering, sorted).

        The soil nodes of the interface facet groups (shafts and pile bases,
        :func:`~pilegroup.geometry.groups.is_interface`), marked by every rank that holds such a
        facet and summed onto the node's owner, so a node whose interface facets lie on other
        ranks is found too and a rank without interface facets has none (collective).
        """
        if self.split is None:
            raise SolverInputError("the soil/structure index sets need separate soil and "
                                   "structure bodies (interface coupling); the piles are tied")
        soil = self.body("soil")
        names = sorted(n for n in self.md.facet_names if groups.is_interface(n))
        facets = np.unique(np.concatenate([self.facets(n) for n in names]
                                          + [np.zeros(0, np.int32)])).astype(np.int32)
        fdim = self.mesh.topology.dim - 1
        nodes = fem.locate_dofs_topological(soil.V, fdim, self.sub_facets(soil, facets))
        imap = soil.V.dofmap.index_map
        mark = la.vector(imap, bs=1, dtype=np.float64)
        mark.array[:] = 0.0
        mark.array[nodes] = 1.0
        mark.scatter_reverse(la.InsertMode.add)
        return np.flatnonzero(mark.array[:imap.size_local] > 0.0).astype(np.int32)

    def soil_band(self, nodes: np.ndarray, layers: int) -> np.ndarray:
        """Owned soil displacement nodes within ``layers`` cell layers of ``nodes``.

        Starting from the owned soil nodes ``nodes`` (local numbering), every layer adds the
        nodes of the soil cells that touch a node found so far; marks made on a rank's cells
        are summed onto the nodes' owners and sent back to their ghosts before the next layer,
        so the band is the same on any rank count (collective; sorted local numbers).
        """
        soil = self.body("soil")
        imap = soil.V.dofmap.index_map
        cells = soil.V.dofmap.list
        mark = la.vector(imap, bs=1, dtype=np.float64)
        mark.array[:] = 0.0
        mark.array[nodes] = 1.0
        mark.scatter_forward()
        for _ in range(layers):
            touched = cells[(mark.array[cells] > 0.0).any(axis=1)]
            mark.array[imap.size_local:] = 0.0  # ghosts carry only this layer's new marks
            mark.array[touched.ravel()] = 1.0
            mark.scatter_reverse(la.InsertMode.add)
            mark.scatter_forward()
        return np.flatnonzero(mark.array[:imap.size_local] > 0.0).astype(np.int32)

    def interface_index_sets(self, A: PETSc.Mat, band_layers: int = 0
                             ) -> tuple[PETSc.IS, PETSc.IS, PETSc.NullSpace]:
        """The structure with the soil around the interface, the soil, and the soil's modes.

        Rows of ``A`` (owned, sorted, whole nodes): the structure's displacement together with
        the soil displacement at :meth:`interface_soil_nodes`, where the interface springs tie
        the soil to the structure, and at the nodes within ``band_layers`` cell layers of them
        (:meth:`soil_band`); the soil displacement rows other than the interface nodes (the
        band belongs to both sets: the blocks overlap there); and the six rigid-body modes of
        those soil nodes (near-nullspace of their block).
        """
        soil, structure = self.body("soil"), self.body("structure")
        offs = self._block_offsets(A)
        n_soil = soil.V.dofmap.index_map.size_local
        at = np.zeros(n_soil, dtype=bool)
        iface = self.interface_soil_nodes()
        at[iface] = True
        band = np.zeros(n_soil, dtype=bool)
        band[self.soil_band(iface, band_layers)] = True
        soil_rows = (offs[0] + 3 * np.arange(n_soil)[:, None] + np.arange(3)).reshape(-1, 3)
        i_t = self.block_of(structure)
        tied = np.concatenate([soil_rows[band].ravel(), np.arange(offs[i_t], offs[i_t + 1])])
        x_rest = soil.V.tabulate_dof_coordinates()[:n_soil][~at]
        return (self._rows_is(np.sort(tied)), self._rows_is(soil_rows[~at].ravel()),
                self.rigid_body_modes(x_rest))

    def _rows_is(self, rows: np.ndarray) -> PETSc.IS:
        """Index set of whole-node displacement rows (block size 3)."""
        is_ = PETSc.IS().createGeneral(rows.astype(PETSc.IntType), comm=self.comm)
        is_.setBlockSize(3)
        return is_

    def rigid_body_modes(self, x: np.ndarray | None = None) -> PETSc.NullSpace:
        """Six rigid-body modes as a PETSc near-nullspace (orthonormal).

        Args:
            x: coordinates ``(n, 3)`` of this rank's owned nodes of the block, in its row order;
                ``None``: every body's owned displacement nodes (the displacement blocks).
        """
        if x is None:
            x = np.concatenate([b.V.tabulate_dof_coordinates()[:b.V.dofmap.index_map.size_local]
                                for b in self.bodies])
        nloc = x.shape[0]
        imap = common.IndexMap(self.comm, nloc)
        basis = [la.vector(imap, bs=3, dtype=PETSc.ScalarType) for _ in range(6)]
        b = [v.array.reshape(-1, 3) for v in basis]
        for i in range(3):
            b[i][:nloc, i] = 1.0
        b[3][:nloc, 0], b[3][:nloc, 1] = -x[:, 1], x[:, 0]
        b[4][:nloc, 0], b[4][:nloc, 2] = x[:, 2], -x[:, 0]
        b[5][:nloc, 2], b[5][:nloc, 1] = x[:, 1], -x[:, 2]
        la.orthonormalize(basis)
        vecs = []
        for v in basis:
            w = PETSc.Vec().createMPI((nloc * 3, PETSc.DECIDE), comm=self.comm)
            w.array[:] = v.array[: nloc * 3]
            vecs.append(w)
        return PETSc.NullSpace().create(vectors=vecs, comm=self.comm)

    def max_displacement(self) -> float:
        """Largest nodal displacement magnitude, m (all ranks)."""
        loc = 0.0
        for b in self.bodies:
            nloc = b.V.dofmap.index_map.size_local
            a = b.u.x.array[: 3 * nloc].reshape(-1, 3)
            loc = max(loc, float(np.sqrt((a**2).sum(axis=1)).max()) if nloc else 0.0)
        return float(self.comm.allreduce(loc, op=MPI.MAX))
