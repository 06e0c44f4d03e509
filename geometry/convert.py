"""gmsh -> DOLFINx: mesh cache and conversion with named cell and facet tags.

(``pilegroup`` itself, imported first as the parent package, imports ``dolfinx_solver`` before
``dolfinx``.)

The gmsh model is built (or read from the cache) on rank 0 only and distributed to all ranks
by ``dolfinx.io.gmsh.model_to_mesh`` with ghost mode ``shared_facet`` (interface integrals over
interior facets need it in parallel).

Cache: ``<cache_dir>/<key>.msh`` plus ``<key>.json`` (counts, quality, timings of the build).
``key`` hashes the :class:`~pilegroup.geometry.spec.GeometrySpec` (geometry and every sizing
parameter), the gmsh version and :data:`BUILDER_VERSION`. The cache directory is, in order:
the ``cache_dir`` argument, the environment variable ``PILEGROUP_MESH_CACHE``,
``~/.cache/pilegroup/meshes``. ``cache_dir=False`` disables the cache.

The mesh is checked before DOLFINx gets it (:func:`check_mesh`, built or read from the
cache): DOLFINx's ``create_mesh`` trusts its input, and e.g. two cells on the same vertices
abort the process (a segmentation fault or heap corruption in serial, ``MPI_Abort`` with
"Invalid rank" under ``mpirun``) instead of raising. Refused with a
:class:`~pilegroup.errors.ScenarioError` naming ``numerics.mesh``, the pile rows, the cap and
the symmetry (raised on every rank): an element that is not an 8-node hexahedron (cells) or a
4-node quadrilateral (facets); a cell with a repeated vertex; two cells on the same vertices;
a degenerate or tangled cell (scaled corner Jacobians not all of one sign and at least
:data:`MIN_SCALED_JACOBIAN` in size, or an edge below :data:`MIN_EDGE_RATIO` x the cell's
longest); two nodes within :data:`DUPLICATE_TOL` x the model's size; a face of more than two
cells, or a boundary face of the cells in no boundary facet group (a hanging node); a node
of a facet in no cell. The cells checked are every hexahedron of the model (every volume the
builder makes is in a cell group, and a cached ``.msh`` holds only the groups' elements), the
facets every quadrilateral. Nodes of no element at all (the centres of the piles' arcs and
other geometric points gmsh meshes as nodes: 112 in the full Pier 667 model as built, none in
its cached ``.msh``) reach no cell and are left alone.
"""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import gmsh
import numpy as np
from dolfinx.io import gmsh as dgmsh
from dolfinx.mesh import GhostMode, create_cell_partitioner
from mpi4py import MPI
from scipy.spatial import cKDTree

from pilegroup.errors import ScenarioError
from pilegroup.fileio import atomic_path, write_text_atomic
from pilegroup.geometry.groups import (
    BOTTOM,
    CAP_SIDE,
    CAP_TOP,
    GROUND,
    SIDES,
    SYM_PLANES,
    head_of,
)
from pilegroup.geometry.meshdata import MeshData
from pilegroup.geometry.pier import build_gmsh_model
from pilegroup.geometry.spec import GeometrySpec

__all__ = [
    "BUILDER_VERSION",
    "CACHE_ENV",
    "DUPLICATE_TOL",
    "MIN_EDGE_RATIO",
    "MIN_SCALED_JACOBIAN",
    "MeshDefect",
    "build_mesh",
    "check_arrays",
    "check_mesh",
    "corner_jacobians",
    "default_cache_dir",
    "ensure_msh",
    "gmsh_session",
]

#: Bump whenever the builder changes the mesh it makes for a given spec (invalidates caches).
BUILDER_VERSION = "pier-5"
CACHE_ENV = "PILEGROUP_MESH_CACHE"


def default_cache_dir() -> Path:
    """``$PILEGROUP_MESH_CACHE`` or ``~/.cache/pilegroup/meshes``."""
    env = os.environ.get(CACHE_ENV)
    return Path(env) if env else Path.home() / ".cache" / "pilegroup" / "meshes"


def _cache_key(spec: GeometrySpec) -> str:
    return spec.cache_key(f"{BUILDER_VERSION}|gmsh {gmsh.__version__}")


def _restore_python_signal_handlers() -> None:
    """Re-arm Python's signal handlers, which gmsh's library replaces at the C level.

    ``gmshInitialize``/``gmshFinalize`` set their own (or the default) actions; Python's
    record (``signal.getsignal``) is unchanged, so setting it again restores every handler
    written in Python (e.g. the stop requests of a run: :mod:`pilegroup.studies.run.interrupt`).
    """
    if threading.current_thread() is not threading.main_thread():
        return
    for s in signal.valid_signals():
        handler = signal.getsignal(s)
        if callable(handler):
            signal.signal(s, handler)


class gmsh_session:  # noqa: N801 - used like a function: ``with gmsh_session(): ...``
    """Context manager: initialise gmsh if needed (quiet, no signal handler), finalise after."""

    def __enter__(self) -> ModuleType:
        self.owner = not gmsh.isInitialized()
        if self.owner:
            gmsh.initialize(readConfigFiles=False, interruptible=False)
            _restore_python_signal_handlers()
        gmsh.option.setNumber("General.Terminal", 0)
        return gmsh

    def __exit__(self, *exc: object) -> None:
        if self.owner and gmsh.isInitialized():
            gmsh.finalize()
            _restore_python_signal_handlers()


def _build_and_write(spec: GeometrySpec, msh: Path | None) -> dict[str, Any]:
    """Build ``spec`` in the current gmsh model; write it to ``msh`` with its info (``.json``)."""
    res = build_gmsh_model(spec)
    info = res.to_dict()
    if msh is not None:
        t0 = time.perf_counter()
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        with atomic_path(msh) as tmp:
            gmsh.write(str(tmp))
        info["timings"]["write_s"] = time.perf_counter() - t0
        write_text_atomic(msh.with_suffix(".json"), json.dumps(info, indent=1))
    return info


def ensure_msh(spec: GeometrySpec, cache_dir: str | Path | None = None,
               force: bool = False) -> tuple[Path, dict[str, Any]]:
    """Path of the cached ``.msh`` of ``spec`` (built now if missing or ``force``) and its info.

    Serial (call it on one rank). ``info["cache_hit"]`` tells whether the mesh was reused.
    """
    cdir = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    with gmsh_session():
        key = _cache_key(spec)
        msh = cdir / f"{key}.msh"
        meta = msh.with_suffix(".json")
        if msh.exists() and meta.exists() and not force:
            info = json.loads(meta.read_text())
            info["cache_hit"] = True
        else:
            gmsh.model.add("ensure")
            info = _build_and_write(spec, msh)
            gmsh.model.remove()
            info["cache_hit"] = False
    info["cache_key"] = key
    info["msh_path"] = str(msh)
    return msh, info


# ------------------------------------------------------------------------------------------------
# the mesh checked before DOLFINx gets it
# ------------------------------------------------------------------------------------------------
#: Two nodes closer than this fraction of the model's bounding-box diagonal are duplicates.
DUPLICATE_TOL = 1e-8
#: A cell's shortest edge must be at least this fraction of its longest.
MIN_EDGE_RATIO = 1e-6
#: Every corner's scaled Jacobian must be at least this in size (and all of one sign).
MIN_SCALED_JACOBIAN = 1e-6

#: The three neighbours of each corner of a hexahedron in gmsh's (and VTK's) node order,
#: ordered so that their edge vectors form a right-handed triple in a positive cell.
_HEX_NEIGHBOURS = np.array([[1, 3, 4], [2, 0, 5], [3, 1, 6], [0, 2, 7],
                            [7, 5, 0], [4, 6, 1], [5, 7, 2], [6, 4, 3]])
#: The six faces of a hexahedron (gmsh node order).
_HEX_FACES = np.array([[0, 3, 2, 1], [0, 1, 5, 4], [0, 4, 7, 3], [1, 2, 6, 5], [2, 3, 7, 6],
                       [4, 5, 6, 7]])


class MeshDefect(ValueError):
    """What is wrong with a mesh (a sentence); :func:`check_mesh` names the scenario keys."""


def corner_jacobians(x: np.ndarray) -> np.ndarray:
    """Scaled corner Jacobians (n, 8) of hexahedra with corner coordinates ``x`` (n, 8, 3).

    The triple product of the three unit edge vectors at each corner: 1 at every corner of a
    positive cube, -1 of an inverted one, 0 where two edges are parallel or one has no length.
    """
    e = x[:, _HEX_NEIGHBOURS, :] - x[:, :, None, :]  # (n, 8, 3 edges, 3)
    norm = np.linalg.norm(e, axis=3)
    unit = np.divide(e, norm[..., None], out=np.zeros_like(e), where=norm[..., None] > 0.0)
    return np.einsum("nci,nci->nc", np.cross(unit[:, :, 0], unit[:, :, 1]), unit[:, :, 2])


def _cell_defects(x: np.ndarray, cells: np.ndarray) -> list[str]:
    """Repeated vertices, duplicate cells, degenerate or inverted cells (node indices)."""
    out = []
    srt = np.sort(cells, axis=1)
    bad = np.flatnonzero(np.any(srt[:, 1:] == srt[:, :-1], axis=1))
    if bad.size:
        out.append(f"{bad.size} cell(s) with a repeated vertex (first: {cells[bad[0]].tolist()})")
    _, first, counts = np.unique(srt, axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        out.append(f"{int(np.sum(counts - 1))} duplicate cell(s) (first on vertices "
                   f"{srt[first[np.argmax(counts > 1)]].tolist()})")
    xc = x[cells]
    sj = corner_jacobians(xc)
    lo, hi = sj.min(axis=1), sj.max(axis=1)
    flat = (hi < MIN_SCALED_JACOBIAN) & (lo > -MIN_SCALED_JACOBIAN)
    mixed = ~((lo >= MIN_SCALED_JACOBIAN) | (hi <= -MIN_SCALED_JACOBIAN))
    edges = np.linalg.norm(xc[:, _HEX_NEIGHBOURS[:, 0]] - xc, axis=2)
    edges = np.concatenate([edges, np.linalg.norm(xc[:, [4, 5, 6, 7]] - xc[:, :4], axis=2)],
                           axis=1)
    short = edges.min(axis=1) < MIN_EDGE_RATIO * edges.max(axis=1)
    bad = np.flatnonzero(flat | mixed | short)
    if bad.size:
        k = bad[0]
        out.append(f"{bad.size} degenerate or inverted cell(s) (first at "
                   f"{np.round(xc[k].mean(axis=0), 3).tolist()} m: scaled corner Jacobians "
                   f"{lo[k]:.3g} to {hi[k]:.3g}, edges {edges[k].min():.3g} to "
                   f"{edges[k].max():.3g} m)")
    return out


def _node_defects(x: np.ndarray, cells: np.ndarray, facets: np.ndarray) -> list[str]:
    """Duplicate nodes of the cells; facet nodes in no cell."""
    out = []
    used = np.unique(cells)
    size = float(np.linalg.norm(x[used].max(axis=0) - x[used].min(axis=0)))
    pairs = cKDTree(x[used]).query_pairs(DUPLICATE_TOL * size, output_type="ndarray")
    if len(pairs):
        a, b = used[pairs[0]]
        out.append(f"{len(pairs)} pair(s) of duplicate nodes (first at "
                   f"{np.round(x[a], 6).tolist()} and {np.round(x[b], 6).tolist()} m)")
    loose = np.setdiff1d(np.unique(facets), used)
    if loose.size:
        out.append(f"{loose.size} facet node(s) in no cell (first at "
                   f"{np.round(x[loose[0]], 6).tolist()} m)")
    return out


def _face_defects(cells: np.ndarray, boundary: np.ndarray) -> list[str]:
    """Faces of more than two cells; boundary faces of the cells in no boundary facet group."""
    out = []
    faces = np.sort(cells[:, _HEX_FACES].reshape(-1, 4), axis=1)
    uniq, counts = np.unique(faces, axis=0, return_counts=True)
    if np.any(counts > 2):
        out.append(f"{int(np.sum(counts > 2))} face(s) shared by more than two cells")
    once = uniq[counts == 1]
    tagged = np.unique(np.sort(boundary, axis=1), axis=0) if len(boundary) else boundary
    view = np.dtype((np.void, once.dtype.itemsize * 4))
    hanging = np.setdiff1d(np.ascontiguousarray(once).view(view),
                           np.ascontiguousarray(tagged.astype(once.dtype)).view(view))
    if hanging.size:
        out.append(f"{hanging.size} boundary face(s) of the cells inside the domain (hanging "
                   "nodes: the mesh is not conforming)")
    return out


def check_arrays(x: np.ndarray, cells: np.ndarray, facets: np.ndarray,
                 boundary: np.ndarray) -> None:
    """Raise :class:`MeshDefect` naming every defect of a hexahedral mesh.

    ``x``: node coordinates (n, 3) m; ``cells``: hexahedra (m, 8) in gmsh's node order;
    ``facets``: every facet element's nodes (k, 4); ``boundary``: the facets of the outer
    boundary groups (b, 4). Indices into ``x``.
    """
    if len(cells) == 0:
        raise MeshDefect("no cells")
    found = (_cell_defects(x, cells) + _node_defects(x, cells, facets)
             + _face_defects(cells, boundary))
    if found:
        raise MeshDefect("; ".join(found))


def _is_boundary(spec: GeometrySpec) -> Callable[[str], bool]:
    """Whether a facet group of ``spec``'s mesh lies on the outer boundary of the domain."""
    outer = {*SIDES, BOTTOM, GROUND, CAP_TOP, CAP_SIDE, *SYM_PLANES.values()}
    return lambda name: name in outer or head_of(name) is not None


def _elements(dim: int, etype: int, n: int, index: np.ndarray,
              entities: list[int] | None = None) -> tuple[np.ndarray, list[int]]:
    """Elements of dimension ``dim`` as (k, n) node indices, and the gmsh types not ``etype``.

    Of the model entities ``entities``, or of every entity of that dimension (``None``).
    """
    blocks = [np.zeros((0, n), dtype=np.int64)]
    other: list[int] = []
    for ent in [-1] if entities is None else entities:
        types, _, nodes = gmsh.model.mesh.getElements(dim, ent)
        for t, nd in zip(types, nodes, strict=True):
            if int(t) != etype:
                other.append(int(t))
                continue
            blocks.append(index[np.asarray(nd, dtype=np.int64)].reshape(-1, n))
    return np.concatenate(blocks), other


def _boundary_entities(spec: GeometrySpec) -> list[int]:
    """The model surfaces in the outer boundary's facet groups."""
    inside = _is_boundary(spec)
    return [int(e) for _, tag in gmsh.model.getPhysicalGroups(2)
            if inside(gmsh.model.getPhysicalName(2, tag))
            for e in gmsh.model.getEntitiesForPhysicalGroup(2, tag)]


def _layout(spec: GeometrySpec) -> str:
    """The scenario's layout keys (and values) that made ``spec``'s mesh, in words."""
    xs = sorted({round(p.x, 9) for p in spec.piles})
    ys = sorted({round(p.y, 9) for p in spec.piles})
    cap = ("no cap" if spec.cap is None else
           f"cap.size_x_m = {spec.cap.x_max - spec.cap.x_min:g}, "
           f"cap.size_y_m = {spec.cap.y_max - spec.cap.y_min:g}")
    return (f"piles: {len(spec.piles)} in {len(xs)} x {len(ys)} rows at x = "
            f"{[float(v) for v in xs]}, y = {[float(v) for v in ys]} m, diameter_m "
            f"{sorted({p.diameter for p in spec.piles})}; {cap}; numerics.symmetry = "
            f"{spec.symmetry!r}")


def check_mesh(spec: GeometrySpec) -> None:
    """Check the mesh of ``spec`` in the current gmsh model (see the module docstring).

    Raises :class:`~pilegroup.errors.ScenarioError` naming the scenario keys that made it and
    every defect found.
    """
    tags, coords, _ = gmsh.model.mesh.getNodes()
    tags = np.asarray(tags, dtype=np.int64)
    index = np.full(int(tags.max()) + 1 if tags.size else 1, -1, dtype=np.int64)
    index[tags] = np.arange(tags.size)
    x = np.asarray(coords, dtype=float).reshape(-1, 3)
    cells, other = _elements(3, 5, 8, index)  # 5: 8-node hexahedron
    facets, other_f = _elements(2, 3, 4, index)  # 3: 4-node quadrangle
    boundary, _ = _elements(2, 3, 4, index, _boundary_entities(spec))
    try:
        if other or other_f:
            raise MeshDefect(f"elements of gmsh types {sorted(set(other + other_f))}, not "
                             "only hexahedra (type 5) and quadrilaterals (type 3)")
        if np.any(cells < 0) or np.any(facets < 0):
            raise MeshDefect("an element refers to a node that does not exist")
        check_arrays(x, cells, facets, boundary)
    except MeshDefect as e:
        sz = spec.sizing
        raise ScenarioError("numerics.mesh", {"size_m": sz.h_pile, "n_circ_min": sz.n_circ_min,
                                              "growth": sz.growth, "far_field_size_m": sz.h_far},
                            f"with {_layout(spec)}: the mesher made an invalid mesh ({e}), which"
                            " DOLFINx cannot take; try another numerics.mesh.size_m or "
                            "n_circ_min (and please report the scenario: the mesher should not "
                            "do this)") from e


def _root_model(spec: GeometrySpec, cache_dir: str | Path | None | bool,
                force: bool) -> dict[str, Any]:
    """Build (or read from the cache) ``spec``'s mesh as the current gmsh model, checked.

    Returns its build information. :func:`check_mesh` raises what would crash DOLFINx's
    ``create_mesh``.
    """
    if cache_dir is False:
        gmsh.model.add("pilegroup")
        info = _build_and_write(spec, None)
        info["cache_hit"] = False
    else:
        path, info = ensure_msh(spec, None if cache_dir is True else cache_dir, force)
        t1 = time.perf_counter()
        gmsh.open(str(path))
        info["timings"]["read_s"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    check_mesh(spec)
    info["timings"]["check_s"] = time.perf_counter() - t1
    return info


def _share_error(comm: MPI.Comm, rank: int, err: Exception | None) -> None:
    """Raise on every rank when mesh generation failed on ``rank`` (with ``err`` there).

    A :class:`~pilegroup.errors.ScenarioError` is raised as one on every rank (the same key,
    value and rule), anything else as ``RuntimeError`` naming it on the other ranks.
    """
    shared = None
    if err is not None:
        shared = ((err.key, err.value, err.allowed, err.unit) if isinstance(err, ScenarioError)
                  else repr(err))
    shared = comm.bcast(shared, root=rank)
    if err is not None:
        raise err
    if isinstance(shared, tuple):
        raise ScenarioError(*shared)
    if shared is not None:
        raise RuntimeError(f"mesh generation failed on rank {rank}: {shared}")


def build_mesh(spec: GeometrySpec, comm: MPI.Comm, cache_dir: str | Path | None | bool = None,
               force: bool = False, rank: int = 0) -> MeshData:
    """Mesh ``spec`` (lengths in m) and distribute it over ``comm``: a :class:`MeshData`.

    gmsh runs on ``rank`` only; every rank gets its part of the mesh with ghost mode
    ``shared_facet``, ``cell_tags`` / ``facet_tags`` and the name -> tag dictionaries.
    ``cache_dir=False`` builds in memory without touching the cache. ``info`` holds the build
    information (``n_hex``, ``min_sj``, timings, ``cache_hit``, ``cache_key``) and the global
    counts ``num_cells`` / ``num_vertices`` of the distributed mesh.
    """
    t0 = time.perf_counter()
    info: dict[str, Any] = {}
    model = None
    with gmsh_session():
        err = None
        if comm.rank == rank:
            try:
                info = _root_model(spec, cache_dir, force)
                model = gmsh.model
            except Exception as e:  # noqa: BLE001 - re-raised on every rank below
                err = e
        _share_error(comm, rank, err)
        t2 = time.perf_counter()
        partitioner = create_cell_partitioner(GhostMode.shared_facet, 2)
        md = dgmsh.model_to_mesh(model, comm, rank, gdim=3, partitioner=partitioner)
        if comm.rank == rank:
            gmsh.model.remove()
    info = comm.bcast(info, root=rank)
    info["timings"]["convert_s"] = time.perf_counter() - t2
    info["timings"]["total_s"] = time.perf_counter() - t0
    mesh = md.mesh
    tdim = mesh.topology.dim
    info["num_cells"] = mesh.topology.index_map(tdim).size_global
    info["num_vertices"] = mesh.topology.index_map(0).size_global
    info["num_ranks"] = comm.size
    cell_names = {k: int(v.tag) for k, v in md.physical_groups.items() if v.dim == tdim}
    facet_names = {k: int(v.tag) for k, v in md.physical_groups.items() if v.dim == tdim - 1}
    return MeshData(mesh=mesh, cell_tags=md.cell_tags, facet_tags=md.facet_tags,
                    cell_names=cell_names, facet_names=facet_names, info=info)
