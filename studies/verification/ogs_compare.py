"""Cross-code verification against OpenGeoSys 6 (OGS, PyPI ``ogs``; the slow test tier only).

Two consolidation problems on one mesh, by pilegroup and by OGS's ``HYDRO_MECHANICS`` process,
same steps and boundary conditions (:func:`compare`): ``fill``, a surcharge ``FILL_KPA`` on the
ground around one elastic pile tied to the soil (head unloaded); ``pile``, that pile loaded at
its head by ``HEAD_KN`` (a uniform pressure on the head). Units kN, m, day (kPa, m/day).
Two weightless linear elastic layers (:data:`LAYERS`; the response to the load only), an
elastic pile (:data:`PILE`) without pore pressure, tied (one conforming mesh, one displacement
field); the quarter ``x, y >= 0`` of the block: rollers on the sides and mirror planes, bottom
fixed and impermeable, ground drained, the rest impermeable. The load acts in full from the
first backward-Euler step (drainage active); both codes take :data:`STEPS` (day).

Mapping: pilegroup solves ``S dp/dt + div(du/dt) - div((k / GAMMA_W) grad p) = 0``, ``S = n /
K_w`` (``solver/forms.py``, ``solver/inputs.py``; ``K_w`` 2.2e6 kPa), Biot coefficient 1; OGS
``S dp/dt + alpha div(du/dt) - div((kappa / mu) grad p) = 0``, ``S = n beta_f + (alpha - n)
(1 - alpha) / K_S`` (OGS ``ProcessLib/HydroMechanics/HydroMechanicsFEM-impl.h``): ``alpha =
1``, ``mu = 1``, ``kappa = k / GAMMA_W``, fluid density ``1 + p / K_w`` (``beta_f = 1 / K_w``
within ``p / K_w`` < 1e-4), no gravity; the pile's pressure is off (``deactivated_subdomains``
on its MaterialID, Biot coefficient and porosity 0 there).

Elements: pilegroup's default (``numerics.element = "auto"``, Q2Q1, ``model/mesh_defaults.py``):
Taylor–Hood with its pressure stabilisation (docs/solver.md). OGS: Taylor–Hood on the 20-node
version of the same hexahedra (mid-edge nodes added here), Gauss order 3. ``pair="Q1Q1"`` runs
pilegroup's stabilised trilinear pair instead (``tau (J J^T / 12) grad(p - p_n) . grad q``,
``tau = 3 / (lambda + 2 mu)``): a diagnostic separating codes from elements.

Tolerances (the project's issue): settlement (mean vertical displacement of the loaded
surface, each code's own shape functions) within 1 % at every output time; excess pore
pressure at the shared vertices (the soil's corner nodes: both codes' pressure nodes) within
``3 % |p_OGS| + 0.5 kPa``. 1 % and 3 % for the element difference (trilinear against quadratic
displacement; the stabilisation's pressure Laplacian ``tau h^2 / 12`` of the increment), 0.5
kPa where the pressure is near zero (drained surface, late times). Measured on the default
mesh (680 cells): ``fill`` passes; ``pile`` does not: pilegroup's Q1Q1 head settlement is
3.4-4.2 % below OGS's (trilinear hexahedra are too stiff in the shaft's shear and at the toe;
2.5-3.1 % at 1224 cells); pilegroup's Q2Q1 is within 0.26 % (pile), 0.03 % (fill) of OGS.

``python -m pilegroup.studies.verification.ogs_compare [fill|pile ...] [Q2Q1]``: the tables.
Needs ``ogs`` beside the running Python (``tools/install-ogs.sh``); serial only.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI
from scipy.spatial import cKDTree

from pilegroup.constitutive.soil import LinearElastic
from pilegroup.geometry import groups
from pilegroup.geometry.convert import build_mesh
from pilegroup.geometry.meshdata import MeshData
from pilegroup.geometry.spec import BlockSpec, GeometrySpec, LayerSpec, MeshSizing, PileSpec
from pilegroup.model.units import K_WATER
from pilegroup.solver import (
    GAMMA_W,
    BiotProblem,
    Discretisation,
    DisplacementBC,
    ElasticSolid,
    PressureBC,
    SoilMaterial,
    SolverOptions,
    SurfaceLoad,
)

__all__ = ["CASES", "LAYERS", "PILE", "STEPS", "build_case_mesh", "compare", "main",
           "ogs_executable", "run_ogs", "run_pilegroup"]


#: The soil layers, top down: thickness (m, None: to the bottom), E (kPa), nu, hydraulic
#: conductivity k (m/day), porosity n (a softer, more permeable clay over a stiffer one).
LAYERS = ({"name": "upper", "t": 3.0, "E": 5.0e3, "nu": 0.3, "k": 5.0e-3, "n": 0.5},
          {"name": "lower", "t": None, "E": 15.0e3, "nu": 0.3, "k": 1.0e-3, "n": 0.4})
#: The pile: E (kPa), nu, diameter and length (m); block plan size and depth below the toe (m).
PILE = {"E": 30.0e6, "nu": 0.2, "d": 0.8, "L": 6.0}
BLOCK = {"width": 8.0, "below_toe": 3.0}
#: Quarter model (x, y >= 0, mirror planes on rollers): 1/MIRRORS of the head; the fill (kPa)
#: and the head load (kN).
MIRRORS, FILL_KPA, HEAD_KN = 4, 50.0, 300.0
#: Time steps (day): the load in full in the first, then held; doubling to 127.5 days (about 3
#: times ``H^2 / c_v`` = 39 days, 9 m drainage path, c_v 2.1 m^2/day of the lower layer).
STEPS = tuple(0.5 * 2.0**i for i in range(8))
#: Case -> its loaded facet group.
CASES = {"fill": groups.GROUND, "pile": groups.head(1)}
#: Tolerances: settlement (relative), pressure (relative to |p_OGS|, plus kPa).
TOL_S, TOL_P_REL, TOL_P_ABS = 0.01, 0.03, 0.5
#: VTK corner order of a DOLFINx hexahedron / quadrilateral (tensor-product numbering).
_HEX_VTK, _QUAD_VTK = [0, 1, 3, 2, 4, 5, 7, 6], [0, 1, 3, 2]
#: VTK's 20-node hexahedron: the corner pairs of its 12 mid-edge nodes (nodes 8 ... 19).
_HEX_EDGES = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4],
                       [0, 4], [1, 5], [2, 6], [3, 7]])
_QUAD_EDGES = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])


def build_case_mesh(h: float = 0.3, n_circ: int = 12, **sizing: float) -> MeshData:
    """The pile in its block by pilegroup's gmsh builder; ``h`` size at pile and surface (m)."""
    spec = GeometrySpec(
        block=BlockSpec(BLOCK["width"], BLOCK["width"], PILE["L"] + BLOCK["below_toe"]),
        layers=tuple(LayerSpec(s["name"], s["t"]) for s in LAYERS),
        piles=(PileSpec(0.0, 0.0, PILE["d"], PILE["L"], 0.0),), cap=None,
        sizing=MeshSizing(**({"h_pile": h, "n_circ_min": n_circ, "near_field_margin": 1.0,
                              "h_far": 1.5, "dz_surface": h, "dz_toe": h, "dz_max": 2 * h,
                              "dz_max_deep": 1.0, "dz_growth": 1.3} | sizing)),
        symmetry="quarter")
    return build_mesh(spec, MPI.COMM_SELF, cache_dir=False)


def _materials() -> dict[str, SoilMaterial | ElasticSolid]:
    return {groups.pile(1): ElasticSolid(PILE["E"], PILE["nu"])} | {
        groups.soil_layer(j + 1): SoilMaterial(LinearElastic(s["E"], s["nu"]),
                                               k_m_per_day=s["k"], porosity=s["n"])
        for j, s in enumerate(LAYERS)}


def _facet_integral(md: MeshData, name: str, f: Any) -> float:
    ds = ufl.Measure("ds", domain=md.mesh, subdomain_data=md.facet_tags)(md.facet_tag(name))
    return float(fem.assemble_scalar(fem.form(f * ds)))


def load_pressure(md: MeshData, case: str) -> float:
    """The uniform pressure (kPa) of a case on its loaded facet group."""
    if case == "fill":
        return FILL_KPA
    return HEAD_KN / (MIRRORS * _facet_integral(md, CASES[case], 1.0))


def run_pilegroup(md: MeshData, case: str, pair: str = "Q2Q1") -> dict[str, Any]:
    """The pilegroup history: ``t`` (day), ``settlement`` (m, down positive), ``p`` per time.

    ``p`` holds the excess pore pressure (kPa) at the soil's pressure nodes ``xp`` (m).
    """
    face = CASES[case]
    bcs = [DisplacementBC(groups.SYM_X, 0), DisplacementBC(groups.SIDE_XMAX, 0),
           DisplacementBC(groups.SYM_Y, 1), DisplacementBC(groups.SIDE_YMAX, 1),
           *(DisplacementBC(groups.BOTTOM, c) for c in range(3))]
    pb = BiotProblem(md, _materials(), Discretisation(pair=pair), displacement_bcs=bcs,
                     pressure_bcs=[PressureBC(groups.GROUND)],
                     loads=[SurfaceLoad(face, load_pressure(md, case))],
                     options=SolverOptions(preset="direct", prefix=f"ogs_{case}_"),
                     self_weight=False)
    area = _facet_integral(md, face, 1.0)
    out: dict[str, Any] = {"t": list(np.cumsum(STEPS)), "settlement": [], "p": [], "area": area,
                           "xp": pb.p.function_space.tabulate_dof_coordinates()}
    for dt in STEPS:
        info = pb.solve_step(dt, 1.0)
        if not info.converged:
            raise RuntimeError(f"pilegroup step dt = {dt} did not converge: {info.message}")
        pb.commit()
        out["settlement"].append(-_facet_integral(md, face, pb.u[2]) / area)
        out["p"].append(pb.p.x.array.copy())
    return out


@dataclass
class OgsMesh:
    """20-node hexahedra (VTK order), MaterialIDs, quad8 faces; pilegroup's nodes first."""

    points: np.ndarray
    cells: np.ndarray
    material: np.ndarray
    faces: dict[str, np.ndarray]
    n_vertices: int


def _orient(x: np.ndarray, hexes: np.ndarray) -> np.ndarray:
    """Hexahedra (VTK corner order) with a positive Jacobian at their centres."""
    c = x[hexes]
    d1 = (c[:, 1] - c[:, 0] + c[:, 2] - c[:, 3] + c[:, 5] - c[:, 4] + c[:, 6] - c[:, 7])
    d2 = (c[:, 3] - c[:, 0] + c[:, 2] - c[:, 1] + c[:, 7] - c[:, 4] + c[:, 6] - c[:, 5])
    d3 = c[:, 4:].sum(axis=1) - c[:, :4].sum(axis=1)
    neg = np.einsum("ij,ij->i", np.cross(d1, d2), d3) < 0
    out = hexes.copy()
    out[neg] = hexes[neg][:, [4, 5, 6, 7, 0, 1, 2, 3]]
    return out


def ogs_mesh(md: MeshData, bc_faces: dict[str, tuple[str, ...]]) -> OgsMesh:
    """Convert ``md`` (serial) to 20-node hexahedra and 8-node boundary quadrilaterals.

    ``bc_faces``: boundary mesh name -> the facet groups it joins.
    """
    msh = md.mesh
    x = msh.geometry.x
    nv = x.shape[0]
    hexes = _orient(x, msh.geometry.dofmaps[0][:, _HEX_VTK])
    pairs = np.sort(hexes[:, _HEX_EDGES].reshape(-1, 2), axis=1)
    keys = pairs[:, 0].astype(np.int64) * nv + pairs[:, 1]
    ukeys, inv = np.unique(keys, return_inverse=True)
    mid = 0.5 * (x[ukeys // nv] + x[ukeys % nv])
    cells = np.hstack([hexes, nv + inv.reshape(-1, 12)])
    material = np.full(hexes.shape[0], -1, dtype=np.int32)
    names = [groups.soil_layer(j + 1) for j in range(len(LAYERS))] + [groups.pile(1)]
    for mid_id, name in enumerate(names):
        material[md.cell_tags.find(md.cell_tag(name))] = mid_id
    if np.any(material < 0):
        raise RuntimeError("a cell of the mesh is neither a soil layer nor the pile")
    msh.topology.create_connectivity(2, 3)
    faces = {}
    for bname, fgroups in bc_faces.items():
        facets = np.concatenate([md.facet_tags.find(md.facet_tag(g)) for g in fgroups])
        quads = dmesh.entities_to_geometry(msh, 2, facets)[:, _QUAD_VTK]
        q = np.sort(quads[:, _QUAD_EDGES].reshape(-1, 2), axis=1)
        qk = q[:, 0].astype(np.int64) * nv + q[:, 1]
        faces[bname] = np.hstack([quads, nv + np.searchsorted(ukeys, qk).reshape(-1, 4)])
    return OgsMesh(np.vstack([x, mid]), cells, material, faces, nv)


def _write_vtu(path: Path, points: np.ndarray, cells: np.ndarray, vtk_type: int,
               cell_data: dict[str, np.ndarray] | None = None) -> None:
    import pyvista as pv

    n = cells.shape[1]
    conn = np.hstack([np.full((cells.shape[0], 1), n), cells]).ravel()
    grid = pv.UnstructuredGrid(conn, np.full(cells.shape[0], vtk_type, dtype=np.uint8),
                               points)
    for k, v in (cell_data or {}).items():
        grid.cell_data[k] = v
    grid.save(path, binary=True)


def write_meshes(folder: Path, om: OgsMesh) -> list[str]:
    """Bulk and boundary VTU files in ``folder`` (bulk ids by OGS's ``identifySubdomains``).

    Returns the mesh names, bulk first.
    """
    _write_vtu(folder / "bulk.vtu", om.points, om.cells, 25, {"MaterialIDs": om.material})
    files = []
    for name, quads in om.faces.items():
        used, local = np.unique(quads, return_inverse=True)
        _write_vtu(folder / f"raw_{name}.vtu", om.points[used], local.reshape(quads.shape), 23)
        files.append(f"raw_{name}.vtu")
    _tool("identifySubdomains", "-f", "-s", "1e-6", "-o", "", "-m", "bulk.vtu", "--", *files,
          cwd=folder)
    for name in om.faces:
        (folder / f"raw_{name}.vtu").replace(folder / f"{name}.vtu")
    return ["bulk", *om.faces]


def ogs_executable(tool: str = "ogs") -> Path:
    """An OGS executable of the running Python's environment (``tools/install-ogs.sh``)."""
    path = Path(sys.executable).parent / tool
    found = str(path) if path.exists() else shutil.which(tool)
    if found is None:
        raise FileNotFoundError(f"{tool} not found next to {sys.executable} nor on PATH: "
                                "run tools/install-ogs.sh")
    return Path(found)


def _tool(tool: str, *args: str, cwd: Path) -> str:
    env = os.environ | {"OMP_NUM_THREADS": os.environ.get("OMP_NUM_THREADS", "1")}
    r = subprocess.run([str(ogs_executable(tool)), *args], cwd=cwd, capture_output=True,
                       text=True, check=False, env=env)
    if r.returncode != 0:
        raise RuntimeError(f"{tool} failed ({r.returncode}):\n{r.stdout[-3000:]}\n"
                           f"{r.stderr[-3000:]}")
    return r.stdout


def _prop(name: str, value: float | str, kind: str = "Constant") -> str:
    return f"<property><name>{name}</name><type>{kind}</type><value>{value}</value></property>"


def _medium(mid: int, perm: float, n: float, alpha: float) -> str:
    rho = ("<property><name>density</name><type>Linear</type><reference_value>1</reference_value>"
           "<independent_variable><variable_name>liquid_phase_pressure</variable_name>"
           f"<reference_condition>0</reference_condition><slope>{1.0 / K_WATER!r}</slope>"
           "</independent_variable></property>")
    return (f'<medium id="{mid}"><phases><phase><type>AqueousLiquid</type><properties>'
            f"{_prop('viscosity', 1.0)}{rho}</properties></phase>"
            f"<phase><type>Solid</type><properties>{_prop('density', 1.0)}</properties>"
            f"</phase></phases><properties>{_prop('permeability', repr(perm))}"
            f"{_prop('porosity', repr(n))}{_prop('biot_coefficient', repr(alpha))}"
            f"{_prop('reference_temperature', 293.15)}</properties></medium>")


def _bc(mesh: str, kind: str, param: str, comp: int | None = None) -> str:
    c = "" if comp is None else f"<component>{comp}</component>"
    return (f"<boundary_condition><mesh>{mesh}</mesh><type>{kind}</type>{c}"
            f"<parameter>{param}</parameter></boundary_condition>")


def prj_text(meshes: list[str], load_mesh: str, pressure: float) -> str:
    """The OGS project: HM, materials per MaterialID, BCs, :data:`STEPS`, ``pressure`` (kPa)."""
    pile_id = len(LAYERS)
    params = {"zero": "0", "zero3": "0 0 0", "q": repr(-pressure)}
    rels, media = [], []
    for i, (E, nu) in enumerate([(s["E"], s["nu"]) for s in LAYERS] + [(PILE["E"], PILE["nu"])]):
        params[f"E{i}"], params[f"nu{i}"] = repr(E), repr(nu)
        rels.append(f'<constitutive_relation id="{i}"><type>LinearElasticIsotropic</type>'
                    f"<youngs_modulus>E{i}</youngs_modulus><poissons_ratio>nu{i}"
                    "</poissons_ratio></constitutive_relation>")
    for i, s in enumerate(LAYERS):
        media.append(_medium(i, s["k"] / GAMMA_W, s["n"], 1.0))
    media.append(_medium(pile_id, 1e-12 * LAYERS[-1]["k"] / GAMMA_W, 0.0, 0.0))
    par = "".join(f"<parameter><name>{k}</name><type>Constant</type><values>{v}</values>"
                  "</parameter>" for k, v in params.items())
    par += ("<parameter><name>load</name><type>CurveScaled</type><curve>ramp</curve>"
            "<parameter>q</parameter></parameter>")
    t_end = float(sum(STEPS))
    steps = "".join(f"<pair><repeat>1</repeat><delta_t>{dt!r}</delta_t></pair>" for dt in STEPS)
    u_bcs = (_bc("x_sides", "Dirichlet", "zero", 0) + _bc("y_sides", "Dirichlet", "zero", 1)
             + "".join(_bc("bottom", "Dirichlet", "zero", c) for c in range(3))
             + _bc(load_mesh, "Neumann", "load", 2))
    lin = ("<linear_solvers><linear_solver><name>lin</name><eigen><solver_type>BiCGSTAB"
           "</solver_type><precon_type>DIAGONAL</precon_type><max_iteration_step>100000"
           "</max_iteration_step><error_tolerance>1e-12</error_tolerance><scaling>true"
           "</scaling></eigen></linear_solver></linear_solvers>")
    return f"""<?xml version="1.0" encoding="ISO-8859-1"?><OpenGeoSysProject>
<meshes>{"".join(f"<mesh>{m}.vtu</mesh>" for m in meshes)}</meshes>
<processes><process><name>HM</name><type>HYDRO_MECHANICS</type>
<integration_order>3</integration_order>{"".join(rels)}<process_variables>
<pressure>pressure</pressure><displacement>displacement</displacement></process_variables>
<specific_body_force>0 0 0</specific_body_force></process></processes>
<media>{"".join(media)}</media><time_loop><processes><process ref="HM">
<nonlinear_solver>newton</nonlinear_solver><convergence_criterion>
<type>PerComponentDeltaX</type><norm_type>NORM2</norm_type><reltols>1e-5 1e-5 1e-5 1e-5</reltols>
</convergence_criterion><time_discretization><type>BackwardEuler</type></time_discretization>
<time_stepping><type>FixedTimeStepping</type><t_initial>0</t_initial><t_end>{t_end!r}</t_end>
<timesteps>{steps}</timesteps></time_stepping></process></processes><output><type>VTK</type>
<prefix>out</prefix><suffix>_ts_{{:timestep}}</suffix><timesteps><pair><repeat>1</repeat>
<each_steps>1</each_steps></pair></timesteps><variables><variable>displacement</variable>
<variable>pressure</variable></variables></output></time_loop><parameters>{par}</parameters>
<curves><curve><name>ramp</name><coords>0 {STEPS[0]!r} {t_end!r}</coords>
<values>0 1 1</values></curve></curves><process_variables><process_variable>
<name>pressure</name><components>1</components><order>1</order>
<initial_condition>zero</initial_condition><boundary_conditions>
{_bc("ground", "Dirichlet", "zero")}</boundary_conditions><deactivated_subdomains>
<deactivated_subdomain><time_interval><start>0</start><end>{2 * t_end!r}</end></time_interval>
<material_ids>{pile_id}</material_ids></deactivated_subdomain></deactivated_subdomains>
</process_variable><process_variable><name>displacement</name><components>3</components>
<order>2</order><initial_condition>zero3</initial_condition><boundary_conditions>{u_bcs}
</boundary_conditions></process_variable></process_variables><nonlinear_solvers>
<nonlinear_solver><name>newton</name><type>Newton</type><max_iter>10</max_iter>
<linear_solver>lin</linear_solver></nonlinear_solver></nonlinear_solvers>{lin}
</OpenGeoSysProject>
"""


def _quad8_mean(points: np.ndarray, quads: np.ndarray, values: np.ndarray
                ) -> tuple[float, float]:
    """(area m^2, mean of nodal ``values``) on quad8 faces: serendipity functions, 3 x 3 Gauss.

    The faces are straight-edged: their geometry is bilinear in the corners.
    """
    g, w = np.polynomial.legendre.leggauss(3)
    xi, eta = (a.ravel() for a in np.meshgrid(g, g))
    wt = np.outer(w, w).ravel()
    cx, cy = np.array([-1, 1, 1, -1]), np.array([-1, -1, 1, 1])
    n8 = np.zeros((xi.size, 8))
    for i in range(4):
        n8[:, i] = 0.25 * (1 + xi * cx[i]) * (1 + eta * cy[i]) * (xi * cx[i] + eta * cy[i] - 1)
    n8[:, 4], n8[:, 6] = 0.5 * (1 - xi**2) * (1 - eta), 0.5 * (1 - xi**2) * (1 + eta)
    n8[:, 5], n8[:, 7] = 0.5 * (1 + xi) * (1 - eta**2), 0.5 * (1 - xi) * (1 - eta**2)
    c = points[quads[:, :4]]
    area = total = 0.0
    for q in range(xi.size):
        dN_dxi = 0.25 * cx * (1 + eta[q] * cy)
        dN_deta = 0.25 * cy * (1 + xi[q] * cx)
        jac = np.linalg.norm(np.cross(np.einsum("i,fid->fd", dN_dxi, c),
                                      np.einsum("i,fid->fd", dN_deta, c)), axis=1)
        area += float(np.sum(wt[q] * jac))
        total += float(np.sum(wt[q] * jac * (values[quads] @ n8[q])))
    return area, total / area


def run_ogs(md: MeshData, case: str, folder: Path) -> dict[str, Any]:
    """OGS's history (files in ``folder``): as :func:`run_pilegroup`, ``wall_s`` its run time."""
    import pyvista as pv

    face = CASES[case]
    om = ogs_mesh(md, {"x_sides": (groups.SYM_X, groups.SIDE_XMAX),
                       "y_sides": (groups.SYM_Y, groups.SIDE_YMAX),
                       "bottom": (groups.BOTTOM,), "ground": (groups.GROUND,),
                       "load": (face,)})
    meshes = write_meshes(folder, om)
    (folder / "case.prj").write_text(prj_text(meshes, "load", load_pressure(md, case)),
                                     encoding="utf-8")
    t0 = time.perf_counter()
    log = _tool("ogs", "-o", "results", "case.prj", cwd=folder)
    out: dict[str, Any] = {"t": [], "settlement": [], "p": [], "xp": om.points[:om.n_vertices],
                           "wall_s": time.perf_counter() - t0, "log": log}
    for ds in ET.parse(folder / "results" / "out.pvd").getroot().iter("DataSet"):
        t = float(ds.get("timestep", "0"))
        if t <= 0.0:
            continue
        grid = pv.read(folder / "results" / str(ds.get("file")))
        if not np.allclose(grid.points, om.points):
            raise RuntimeError("OGS reordered the mesh nodes")
        area, mean_uz = _quad8_mean(om.points, om.faces["load"],
                                    np.asarray(grid.point_data["displacement"])[:, 2])
        out["t"].append(t)
        out["settlement"].append(-mean_uz)
        out["p"].append(np.asarray(grid.point_data["pressure"])[:om.n_vertices].copy())
        out["area"] = area
    return out


def _pressure_rows(pg: dict[str, Any], og: dict[str, Any]) -> list[dict[str, Any]]:
    """Per output time: the worst pressure node against ``TOL_P_REL |p_OGS| + TOL_P_ABS``."""
    dist, idx = cKDTree(og["xp"]).query(pg["xp"])
    if dist.max() > 1e-8:
        raise RuntimeError(f"a pressure node is {dist.max():.3g} m from every OGS node")
    rows = []
    for t, p_pg, p_og in zip(pg["t"], pg["p"], og["p"], strict=True):
        ref = p_og[idx]
        diff = np.abs(p_pg - ref)
        ratio = diff / (TOL_P_REL * np.abs(ref) + TOL_P_ABS)
        k = int(np.argmax(ratio))
        rows.append({"t_day": t, "ratio": float(ratio[k]), "p_pg_kPa": float(p_pg[k]),
                     "p_ogs_kPa": float(ref[k]), "x_m": pg["xp"][k].tolist(),
                     "max_abs_diff_kPa": float(diff.max()),
                     "max_p_ogs_kPa": float(np.abs(ref).max())})
    return rows


def compare(case: str, pair: str = "Q2Q1", keep: Path | None = None) -> dict[str, Any]:
    """Run ``case`` (``fill`` or ``pile``) in both codes and compare them (serial).

    Returns ``settlement`` rows (``t_day``, both settlements in m, ``error`` relative to OGS),
    ``pressure`` rows (per time the worst vertex: ``ratio`` = ``|dp| / (0.03 |p_OGS| + 0.5
    kPa)``, its pressures and place, the largest ``|dp|``), the worst of each, ``passed``,
    wall times (s) and sizes. ``pair``: pilegroup's element pair (default: its default);
    ``keep``: a folder for OGS's files (else a temporary one, removed).
    """
    if case not in CASES:
        raise KeyError(f"case {case!r}; known: {sorted(CASES)}")
    if MPI.COMM_WORLD.size > 1:
        raise RuntimeError("ogs_compare runs serially (one rank)")
    t0 = time.perf_counter()
    md = build_case_mesh()
    pg = run_pilegroup(md, case, pair)
    t_pg = time.perf_counter() - t0
    folder = keep or Path(tempfile.mkdtemp(prefix=f"ogs-{case}-"))
    folder.mkdir(parents=True, exist_ok=True)
    try:
        og = run_ogs(md, case, folder)
    finally:
        if keep is None:
            shutil.rmtree(folder, ignore_errors=True)
    if not np.allclose(pg["t"], og["t"], rtol=1e-12, atol=1e-12):
        raise RuntimeError(f"output times differ: {pg['t']} and {og['t']}")
    srows = [{"t_day": t, "s_pg_m": a, "s_ogs_m": b, "error": abs(a - b) / abs(b)}
             for t, a, b in zip(pg["t"], pg["settlement"], og["settlement"], strict=True)]
    prows = _pressure_rows(pg, og)
    s_err, p_ratio = max(r["error"] for r in srows), max(r["ratio"] for r in prows)
    return {"case": case, "pair": pair, "settlement": srows, "pressure": prows,
            "max_settlement_error": s_err, "max_pressure_ratio": p_ratio,
            "passed": bool(s_err <= TOL_S and p_ratio <= 1.0),
            "area_m2": (pg["area"], og["area"]), "load_kPa": load_pressure(md, case),
            "cells": int(md.mesh.topology.index_map(3).size_local),
            "ogs_nodes": int(og["xp"].shape[0]),
            "wall_s": {"pilegroup": t_pg, "ogs": og["wall_s"],
                       "total": time.perf_counter() - t0}}


def format_table(res: dict[str, Any]) -> str:
    """One case's comparison as text: settlement and the worst pressure node per time."""
    wall = ", ".join(f"{k} {v:.1f}" for k, v in res["wall_s"].items())
    lines = [f"{res['case']} (pilegroup {res['pair']}): load {res['load_kPa']:.2f} kPa, "
             f"{res['cells']} cells, passed {res['passed']} (wall s: {wall})",
             f"{'t day':>7} {'s_pg mm':>8} {'s_OGS mm':>8} {'err %':>6} {'dp/tol':>6} "
             f"{'p_pg':>7} {'p_OGS':>7} {'max|dp|':>7}  worst node (x, y, z) m"]
    for s, p in zip(res["settlement"], res["pressure"], strict=True):
        x = ", ".join(f"{v:.2f}" for v in p["x_m"])
        lines.append(f"{s['t_day']:7.2f} {1e3 * s['s_pg_m']:8.4f} {1e3 * s['s_ogs_m']:8.4f} "
                     f"{100 * s['error']:6.3f} {p['ratio']:6.3f} {p['p_pg_kPa']:7.3f} "
                     f"{p['p_ogs_kPa']:7.3f} {p['max_abs_diff_kPa']:7.3f}  ({x})")
    lines.append(f"worst: settlement {100 * res['max_settlement_error']:.3f} % (tolerance "
                 f"{100 * TOL_S:g} %), pressure {res['max_pressure_ratio']:.3f} of "
                 f"({100 * TOL_P_REL:g} % |p_OGS| + {TOL_P_ABS:g} kPa); pressures in kPa")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Print the tables of the cases named (default: all; ``Q1Q1``: that pair); 1 if one fails."""
    args = list(sys.argv[1:] if argv is None else argv)
    pair = "Q1Q1" if "Q1Q1" in args else "Q2Q1"
    ok = True
    for name in [a for a in args if a in CASES] or list(CASES):
        res = compare(name, pair)
        print(format_table(res), flush=True)
        ok &= res["passed"]
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
