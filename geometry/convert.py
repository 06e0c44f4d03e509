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
"""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path
from types import ModuleType
from typing import Any

import gmsh
from dolfinx.io import gmsh as dgmsh
from dolfinx.mesh import GhostMode, create_cell_partitioner
from mpi4py import MPI

from pilegroup.fileio import atomic_path, write_text_atomic
from pilegroup.geometry.meshdata import MeshData
from pilegroup.geometry.pier import build_gmsh_model
from pilegroup.geometry.spec import GeometrySpec

__all__ = [
    "BUILDER_VERSION",
    "CACHE_ENV",
    "build_mesh",
    "default_cache_dir",
    "ensure_msh",
    "gmsh_session",
]

#: Bump whenever the builder changes the mesh it makes for a given spec (invalidates caches).
BUILDER_VERSION = "pier-3"
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
        if comm.rank == rank:
            try:
                if cache_dir is False:
                    gmsh.model.add("pilegroup")
                    info = _build_and_write(spec, None)
                    info["cache_hit"] = False
                else:
                    path, info = ensure_msh(spec, None if cache_dir is True else cache_dir,
                                            force)
                    t1 = time.perf_counter()
                    gmsh.open(str(path))
                    info["timings"]["read_s"] = time.perf_counter() - t1
                model = gmsh.model
                err = None
            except Exception as e:  # noqa: BLE001 - re-raised on every rank below
                err = e
        else:
            err = None
        errs = comm.allgather(None if err is None else repr(err))
        if err is not None:
            raise err
        if any(errs):
            raise RuntimeError(f"mesh generation failed on rank {rank}: {errs[rank]}")
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
