"""The weak form of the coupled problem, one builder per physical term.

Residual ``F[i]`` and Jacobian ``J[i][j]`` blocks follow the block order of
:class:`~pilegroup.solver.layout.BlockLayout` (``[u, p, u_structure]``). Physics (docs/model.md;
units kN, m, day; tension positive; ``p`` excess pore pressure, compression positive):

* momentum: ``int sigma' : eps(v) - p div v + b' . v``, ``b' = (gamma_sat - GAMMA_W) e_z`` the
  buoyant weight (with ``self_weight``; the total weight and no ``p`` term in the dry soil above
  a water table); the stress and its consistent tangent come from the quadrature-point state;
* mass balance, backward Euler (multiplied by dt):
  ``S (p - p_n) + div(u - u_n) - dt div((k/GAMMA_W) grad p) = 0``, ``S = n / K_w``, in the
  saturated soil (the dry soil's pressure unknowns are held, ``solver/constraints.py``);
* pressure stabilisation of both pairs: ``tau int (J J^T / 12) grad(p - p_n) . grad q``, a
  pressure Laplacian in each cell's own metric (``J`` the Jacobian of the map from the unit
  cube), ``tau = 3 / (lambda + 2 mu)`` (Q1-Q1) or ``2 / (lambda + 2 mu)`` (Q2-Q1) per soil
  material (:func:`projection_tau`);
* surface loads: ``int c n . v`` with a Constant pressure per load;
* interface: the law's effective traction plus the excess pore pressure on the pile surfaces;
* fixed-stress preconditioning term ``(1/K_dr) M`` on the pressure block.

Every cell term uses the Gauss rule of degree ``2 * u_degree`` (exact on affine cells for the
products of Q2-Q1 and Q1-Q1); UFL's estimate for hexahedra would use up to 8x more points.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import ufl
from dolfinx import default_scalar_type, fem
from dolfinx import mesh as dmesh

from pilegroup.errors import SolverInputError
from pilegroup.solver.geostatic import Z_TOL, SoilColumn
from pilegroup.solver.inputs import (
    GAMMA_W,
    Discretisation,
    FaceAction,
    SoilMaterial,
    SurfaceLoad,
)
from pilegroup.solver.interface import NodalInterface
from pilegroup.solver.layout import BlockLayout, Body, eps_mandel

Form = ufl.Form | None
#: A cell tag no cell carries (the measure of the empty padding terms, ``pad_parts``).
EMPTY_TAG = 2**31 - 2
#: The subdomain id of a body's tangent term over the cells whose tangent changed: the cells are
#: given to the form at each assembly (``MonolithicAlgebra._update_kept``). Not ``dx``'s default
#: id: DOLFINx integrates a default integral over every cell whatever cells it is given.
CHANGED_TAG = 2**31 - 3


@dataclass
class BlockForms:
    """Residual blocks ``F[i]`` and Jacobian blocks ``J[i][j]`` (UFL forms, summed by term).

    Each term of ``J`` is also in one part: ``J_each``, the time step's flow term, changes from
    one Newton iteration to the next; ``J_kept``, the rest but the interface's tangent (which
    the interface adds node by node, ``part="itf"``), changes only with the quadrature-point
    tangents, the constraints and the cell coefficients, so its matrix is kept between
    assemblies (:meth:`~pilegroup.solver.algebra.MonolithicAlgebra.assemble_jacobian`).
    """

    n: int
    F: list[Form] = field(init=False)
    J: list[list[Form]] = field(init=False)
    J_kept: list[list[Form]] = field(init=False)
    J_each: list[list[Form]] = field(init=False)

    def __post_init__(self) -> None:
        self.F = [None] * self.n
        self.J, self.J_kept, self.J_each = (
            [[None] * self.n for _ in range(self.n)] for _ in range(3))

    def add_F(self, i: int, form: ufl.Form) -> None:
        """Add ``form`` to residual block ``i``."""
        self.F[i] = form if self.F[i] is None else self.F[i] + form

    def pad_diagonal(self, empty: Sequence[ufl.Form]) -> None:
        """Add ``empty[i]`` (a term over no cell) to the diagonal blocks of ``J_kept``, ``J_each``.

        Each part then assembles as a blocked form (a form in every row and on the diagonal).
        """
        for J in (self.J_kept, self.J_each):
            for i, form in enumerate(empty):
                J[i][i] = form if J[i][i] is None else J[i][i] + form

    def add_J(self, i: int, j: int, form: ufl.Form, part: str = "kept") -> None:
        """Add ``form`` to Jacobian block ``(i, j)`` and to its ``part`` of ``J``.

        ``part``: ``"kept"``, ``"each"`` or ``"itf"`` (in ``J`` only; the class docstring).
        """
        parts = {"kept": [self.J_kept], "each": [self.J_each], "itf": []}
        for J in [self.J, *parts[part]]:
            J[i][j] = form if J[i][j] is None else J[i][j] + form


#: ``tau (lambda + 2 mu)`` of each element pair (:func:`projection_tau`).
TAU_SCALE = {"Q1Q1": 3.0, "Q2Q1": 2.0}


def projection_tau(K: float, G: float, pair: str) -> float:
    """Pressure stabilisation parameter ``tau = TAU_SCALE[pair] / (lambda + 2 mu)``, 1/kPa.

    Source: the stabilised linear pair of Aguilar, Gaspar, Lisbona & Rodrigo (Int. J. Numer.
    Meth. Engng 75, 2008, 1282-1300) and Rodrigo, Gaspar, Hu & Zikatanov (Comput. Methods Appl.
    Mech. Engrg 298, 2016, 183-204) adds ``beta int grad(p - p_n) . grad q`` to the mass balance
    and chooses ``beta`` from the 1D undrained pressure operator, ``1/(lambda + 2 mu)`` times a
    mass matrix in which the element's strains are exact:

    * Q1-Q1: the strain is constant per cell, the one-point mass matrix ``h/4 [1 1; 1 1]``
      (the checkerboard in its kernel); ``beta = h^2 / (4 (lambda + 2 mu))`` adds
      ``h/4 [1 -1; -1 1]`` and makes it the lumped mass matrix ``h/2 I``;
    * Q2-Q1: the strain is linear per cell, the consistent mass matrix ``h/6 [2 1; 1 2]``
      (positive off-diagonal: the pressure overshoots next to a drained face when the step
      is short, ``dt < h^2 / (6 c_v)``); ``beta = h^2 / (6 (lambda + 2 mu))`` adds
      ``h/6 [1 -1; -1 1]`` and makes it the same ``h/2 I``.

    An M-matrix: the pressure is monotone at any time step. The term of
    :meth:`FormBuilder.stabilisation` is ``tau (h_n^2 / 12)`` in each direction ``n`` of a box
    cell, so ``tau h_n^2 / 12 = beta`` gives ``tau = 3 / (lambda + 2 mu)`` (Q1-Q1) and
    ``2 / (lambda + 2 mu)`` (Q2-Q1) with each direction's own cell size (docs/solver.md).
    """
    return TAU_SCALE[pair] / (K + 4.0 * G / 3.0)


#: Smallest mean effective stress (kPa) at which a stress-dependent law's moduli are taken.
P_REF_MIN = 1.0


def representative_moduli(mat: SoilMaterial, column: SoilColumn, name: str
                          ) -> tuple[float, float]:
    """(bulk K, shear G) of soil group ``name``'s elastic part for ``tau`` and ``beta``, kPa.

    A law whose elastic moduli follow the stress (Modified Cam Clay, Soft Soil Creep: its
    ``elastic_moduli(p)``) gives them at the mean effective stress at rest at its layer's
    mid-depth, ``p = (1 + 2 K0) sigma'_v / 3`` (at least :data:`P_REF_MIN`), one value for the
    whole layer (docs/model.md, "Soil models per layer"); every other law its constant moduli.
    """
    moduli = getattr(mat.law, "elastic_moduli", None)
    if moduli is None:
        return mat.elastic_moduli()
    lay = column.by_name[name]
    z = np.array([0.5 * (lay.z_min + min(lay.z_max, column.z_top))])
    p = -(1.0 + 2.0 * lay.k0) / 3.0 * float(column.sigma_v(z)[0])
    return moduli(max(p, P_REF_MIN))


class Coefficients:
    """Cell-wise (DG0, parent mesh) material coefficients of the soil terms.

    ``S`` storage (1/kPa), ``mob`` mobility k/GAMMA_W (m^2/(kPa day); the vertical one when a
    layer is anisotropic, ``mob_h`` then the horizontal one, else ``None``), ``gam`` the unit
    weight the skeleton carries (kN/m^3: buoyant, total above the water table; solids take that
    of the layer they replace), ``sat`` 1 in saturated cells and 0 above the water table
    (``None`` when no soil is above it), ``tau`` stabilisation
    ``stab_factor * projection_tau(K, G, pair)`` (1/kPa), ``beta`` fixed-stress ``1/K`` (1/kPa); the
    moduli are those of each material's elastic part (the elastic moduli of a plastic soil; a
    stress-dependent one's at its layer's mid-depth, :func:`representative_moduli`).
    """

    def __init__(self, layout: BlockLayout, disc: Discretisation, column: SoilColumn) -> None:
        mesh, md = layout.mesh, layout.md
        D0 = fem.functionspace(mesh, ("DG", 0))
        self.S, self.mob, self.gam, self.tau, self.beta = (fem.Function(D0) for _ in range(5))
        soils = [m for m in layout.materials.values() if isinstance(m, SoilMaterial)]
        # horizontal mobility, only when a layer is anisotropic (else ``mob`` acts everywhere)
        self.mob_h = fem.Function(D0) if any(m.k_h_m_per_day is not None for m in soils) \
            else None
        # 1 in saturated cells, 0 above the water table; only when there is soil above it
        self.sat = fem.Function(D0) if column.has_dry else None
        for name, mat in layout.materials.items():
            cells = md.cell_tags.find(md.cell_tag(name))
            zc = dmesh.compute_midpoints(mesh, mesh.topology.dim, cells)[:, 2]
            if not isinstance(mat, SoilMaterial):
                self.gam.x.array[cells] = column.skeleton_weight(zc)
                continue
            K, G = representative_moduli(mat, column, name)
            wet = column.wet(zc)
            self.S.x.array[cells] = mat.storage * wet
            self.mob.x.array[cells] = mat.mobility * wet
            if self.mob_h is not None:
                self.mob_h.x.array[cells] = mat.mobility_h * wet
            dry = mat.gamma_sat if mat.gamma_unsat is None else mat.gamma_unsat
            self.gam.x.array[cells] = np.where(wet, mat.gamma_sat - GAMMA_W, dry)
            self.tau.x.array[cells] = disc.stab_factor * projection_tau(K, G, disc.pair) * wet
            self.beta.x.array[cells] = 1.0 / K * wet
            if self.sat is not None:
                self.sat.x.array[cells] = wet
        self.dt = fem.Constant(mesh, default_scalar_type(0.0))
        if column.has_dry:
            _check_cells_off_water_table(layout, column.z_w)


class FormBuilder:
    """Test and trial functions, measures and coefficients shared by the term builders."""

    def __init__(self, layout: BlockLayout, disc: Discretisation, coef: Coefficients) -> None:
        self.layout, self.disc, self.coef = layout, disc, coef
        md, mesh = layout.md, layout.mesh
        q_md = {"quadrature_degree": disc.quadrature_degree}
        self.dx_all = ufl.Measure("dx", domain=mesh, subdomain_data=md.cell_tags, metadata=q_md)
        self.dx = self.dx_all(layout.soil_tags) if layout.has_solids else \
            ufl.Measure("dx", domain=mesh, metadata=q_md)
        self.ds = ufl.Measure("ds", domain=mesh, subdomain_data=md.facet_tags)
        self.tests = [ufl.TestFunction(b.V) for b in layout.bodies]
        self.trials = [ufl.TrialFunction(b.V) for b in layout.bodies]
        self.q, self.dp = ufl.TestFunction(layout.Q), ufl.TrialFunction(layout.Q)
        self.forms = BlockForms(len(layout.fields))

    def dx_body(self, b: Body) -> ufl.Measure:
        """Cell measure over a body's cells."""
        return self.dx_all(b.tags) if self.layout.has_solids else self.dx

    def internal_force(self, b: Body) -> ufl.Form:
        """``int sigma' : eps(v)`` of body ``b`` (its internal force)."""
        v = self.tests[self.layout.bodies.index(b)]
        return ufl.inner(b.qp.stress, eps_mandel(v)) * self.dx_body(b)

    def pad_parts(self) -> list[ufl.Form]:
        """Diagonal terms over no cell for the parts of ``J`` (:meth:`BlockForms.pad_diagonal`).

        The measure is the parent's cells with a tag no cell has: nothing is integrated, but
        DOLFINx's blocked assembly then finds a form in every row (and on the diagonal of
        each block with boundary conditions). Returns the diagonal's empty terms.
        """
        lay = self.layout
        none = ufl.Measure("dx", domain=lay.mesh, subdomain_data=lay.md.cell_tags,
                           subdomain_id=EMPTY_TAG)
        empty: list[ufl.Form] = [None] * self.forms.n
        for b, v, du in zip(lay.bodies, self.tests, self.trials, strict=True):
            empty[lay.block_of(b)] = ufl.inner(du, v) * none
        empty[1] = self.dp * self.q * none
        self.forms.pad_diagonal(empty)
        return empty

    def tangent(self, b: Body, changed: bool = False) -> ufl.Form:
        """``int (C_t : eps(du)) : eps(v)`` of body ``b`` (its tangent stiffness).

        ``changed``: over the subdomain :data:`CHANGED_TAG` (the cells given at assembly)
        instead of the body's cells.
        """
        i = self.layout.bodies.index(b)
        dx = self.dx_all(CHANGED_TAG) if changed else self.dx_body(b)
        return ufl.inner(ufl.dot(b.qp.tangent, eps_mandel(self.trials[i])),
                         eps_mandel(self.tests[i])) * dx

    def momentum(self, self_weight: bool) -> None:
        """Effective stress, buoyant weight and the pore-pressure coupling ``-p div v``."""
        lay, f = self.layout, self.forms
        for b, v in zip(lay.bodies, self.tests, strict=True):
            i = lay.block_of(b)
            f.add_F(i, self.internal_force(b))
            if self_weight:
                f.add_F(i, self.coef.gam * v[2] * self.dx_body(b))
            f.add_J(i, i, self.tangent(b))
        v0, du0 = self.tests[0], self.trials[0]
        f.add_F(0, -self.wet(lay.p) * ufl.div(v0) * self.dx)
        f.add_J(0, 1, -self.wet(self.dp) * ufl.div(v0) * self.dx)
        f.add_J(1, 0, self.wet(ufl.div(du0)) * self.q * self.dx)

    def wet(self, expr: ufl.core.expr.Expr, side: str | None = None) -> ufl.core.expr.Expr:
        """``expr`` in saturated soil, 0 above the water table (``side``: a facet's side).

        The soil above the water table is dry: its skeleton carries no pore pressure and adds
        no volume change to the water's mass balance.
        """
        sat = self.coef.sat
        if sat is None:
            return expr
        return sat * expr if side is None else sat(side) * expr

    def surface_loads(self, loads: Sequence[SurfaceLoad | FaceAction]
                      ) -> list[tuple[SurfaceLoad | FaceAction, fem.Constant]]:
        """``int c n . v`` (a pressure) or ``-int c t . v`` (a face action) on each load.

        ``t`` is a face action's unit traction; returns the loads with their amplitude
        constant ``c``.
        """
        lay, md = self.layout, self.layout.md
        nrm = ufl.FacetNormal(lay.mesh)
        out = []
        for ld in loads:
            c = fem.Constant(lay.mesh, default_scalar_type(0.0))
            b = lay.body_of_facet(ld.facet)
            v = self.tests[lay.bodies.index(b)]
            ds = self.ds(md.facet_tag(ld.facet))
            if isinstance(ld, FaceAction):
                term = -c * ufl.inner(_unit_traction(lay.mesh, ld), v) * ds
            else:
                term = c * _plan_window(lay.mesh, ld) * ufl.inner(nrm, v) * ds
            self.forms.add_F(lay.block_of(b), term)
            out.append((ld, c))
        return out

    def mass_balance(self) -> None:
        """Storage, volume change and Darcy flow (backward Euler, times dt)."""
        lay, c, q, dp = self.layout, self.coef, self.q, self.dp
        p, p_n, u, u_n = lay.p, lay.p_n, lay.fields[0], lay.fields_n[0]
        dx = self.dx
        self.forms.add_F(1, (c.S * (p - p_n) + self.wet(ufl.div(u - u_n))) * q * dx
                         + c.dt * self._darcy(p, q) * dx)
        self.forms.add_J(1, 1, c.S * dp * q * dx + c.dt * self._darcy(dp, q) * dx,
                         part="each")

    def _darcy(self, p: ufl.core.expr.Expr, q: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """``mob grad p . grad q``; with anisotropic layers ``mob_h`` acts in x and y."""
        c, gp, gq = self.coef, ufl.grad(p), ufl.grad(q)
        if c.mob_h is None:
            return c.mob * ufl.inner(gp, gq)
        return c.mob_h * (gp[0] * gq[0] + gp[1] * gq[1]) + c.mob * gp[2] * gq[2]

    def stabilisation(self) -> None:
        """Pressure stabilisation: a Laplacian in the cell's metric (both pairs).

        ``tau int (J J^T / 12) grad(p - p_n) . grad q`` on the soil cells, ``J`` the Jacobian
        of the map from the unit cube (its columns are the cell's edge vectors), ``tau`` of
        :func:`projection_tau`. On a box cell of sides ``h_x, h_y, h_z`` it is
        ``tau (h_i^2 / 12) int d_i p d_i q`` in each direction: the ``beta`` of
        :func:`projection_tau` with each direction's own ``h`` (a monotone 1D pressure in a
        drained step of any size). It is positive semi-definite on every cell,
        graded, stretched or not a parallelepiped (docs/solver.md, "Pressure stabilisation").
        """
        lay, tau, q, dp = self.layout, self.coef.tau, self.q, self.dp
        J = ufl.Jacobian(lay.mesh)
        metric = J * J.T / 12.0
        dpn = lay.p - lay.p_n
        self.forms.add_F(1, tau * ufl.inner(metric * ufl.grad(dpn), ufl.grad(q)) * self.dx)
        self.forms.add_J(1, 1, tau * ufl.inner(metric * ufl.grad(dp), ufl.grad(q)) * self.dx)

    def interface(self, itf: NodalInterface) -> None:
        """Interface traction (law + excess pore pressure) between structure and soil.

        The law gives the effective traction ``t'``; the total traction on the pile is
        ``t' - p n`` (``n`` the structure's outward normal, ``p`` the excess pore pressure on
        the soil side), so the residuals get ``-int (t' - p n) . v_str`` and
        ``+int (t' - p n) . v_soil`` over the pile surfaces.
        """
        lay, f = self.layout, self.forms
        soil, struct = lay.body("soil"), lay.body("structure")
        i_s, i_t = lay.block_of(soil), lay.block_of(struct)
        v_s, v_t = self.tests[0], self.tests[1]
        du_s, du_t = self.trials[0], self.trials[1]
        r_t, r_s = itf.residual_forms(v_t, v_s)
        n = ufl.FacetNormal(lay.mesh)("+")
        dS = itf.surface_measure()
        p = self.wet(lay.p("-"), "-")
        f.add_F(i_t, r_t + p * ufl.inner(n, v_t("+")) * dS)
        f.add_F(i_s, r_s - p * ufl.inner(n, v_s("-")) * dS)
        Ji = itf.jacobian_forms(du_t, du_s, v_t, v_s)
        f.add_J(i_t, i_t, Ji[0][0], part="itf")
        f.add_J(i_t, i_s, Ji[0][1], part="itf")
        f.add_J(i_s, i_t, Ji[1][0], part="itf")
        f.add_J(i_s, i_s, Ji[1][1], part="itf")
        dp = self.wet(self.dp("-"), "-")
        f.add_J(i_s, 1, -dp * ufl.inner(n, v_s("-")) * dS)
        f.add_J(i_t, 1, dp * ufl.inner(n, v_t("+")) * dS)

    def fixed_stress(self) -> list[list[Form]]:
        """Preconditioning blocks: ``(1/K) M`` on p, zero-valued mass blocks on u.

        The preconditioning matrix is ``J + M_beta``; the zero u blocks give it J's sparsity.
        """
        lay = self.layout
        zero = fem.Constant(lay.mesh, default_scalar_type(0.0))
        P = BlockForms(len(lay.fields))
        for b, v, du in zip(lay.bodies, self.tests, self.trials, strict=True):
            i = lay.block_of(b)
            P.add_J(i, i, zero * ufl.inner(du, v) * self.dx_body(b))
        P.add_J(1, 1, self.coef.beta * self.dp * self.q * self.dx)
        return P.J


def _check_cells_off_water_table(layout: BlockLayout, z_w: float) -> None:
    """No cell reaches across the water table: the mesh has a surface there (collective).

    The unit weight, the pressure terms and the drained boundary change at the water table, so
    it must lie on cell faces (``GeometrySpec.levels``).
    """
    mesh = layout.mesh
    x = mesh.geometry.x[:, 2]
    imap = mesh.topology.index_map(mesh.topology.dim)
    z = x[mesh.geometry.dofmaps[0][:imap.size_local]]
    cut = mesh.comm.allreduce(int(np.sum((z.min(axis=1) < z_w - Z_TOL)
                                         & (z.max(axis=1) > z_w + Z_TOL))))
    if cut > 0:
        raise SolverInputError(f"water table z = {z_w:g} m: {cut} cells reach across it;"
                               " allowed: a mesh with a horizontal surface at the water table"
                               " (GeometrySpec.levels)")


def interface_force_form(layout: BlockLayout, itf: NodalInterface, coef: Coefficients
                         ) -> ufl.Form:
    """``int (t' - p n) . v`` over the pile surfaces, ``v`` a structure test function.

    The force (kN per structure dof) the soil exerts on the structure through the interface:
    the interface's part of the structure's external force (:meth:`FormBuilder.interface`;
    ``coef.sat``: no pore pressure above the water table).
    """
    soil, struct = layout.body("soil"), layout.body("structure")
    v_t, v_s = ufl.TestFunction(struct.V), ufl.TestFunction(soil.V)
    r_t, _ = itf.residual_forms(v_t, v_s)
    n = ufl.FacetNormal(layout.mesh)("+")
    p = layout.p("-") if coef.sat is None else coef.sat("-") * layout.p("-")
    return -(r_t + p * ufl.inner(n, v_t("+")) * itf.surface_measure())


def _unit_traction(mesh: dmesh.Mesh, fa: FaceAction) -> ufl.core.expr.Expr:
    """The traction (kPa) of face action ``fa`` at unit amplitude (see :class:`FaceAction`)."""
    x = ufl.SpatialCoordinate(mesh)
    dx_, dy_ = x[0] - fa.centre[0], x[1] - fa.centre[1]
    ixx, iyy = fa.inertia
    k = fa.component
    if k < 3:
        return ufl.as_vector([1.0 / fa.area if j == k else 0.0 for j in range(3)])
    if k == 3:
        return ufl.as_vector([0.0, 0.0, dy_ / ixx])
    if k == 4:
        return ufl.as_vector([0.0, 0.0, -dx_ / iyy])
    return ufl.as_vector([-dy_, dx_, 0.0]) / (ixx + iyy)


def _plan_window(mesh: dmesh.Mesh, ld: SurfaceLoad) -> ufl.core.expr.Expr | float:
    """1 where load ``ld`` acts in plan (inside its ``area``, or everywhere), else 0."""
    if ld.area is None:
        return 1.0
    x, (x0, x1, y0, y1) = ufl.SpatialCoordinate(mesh), ld.area
    inside = ufl.And(ufl.And(ufl.ge(x[0], x0), ufl.le(x[0], x1)),
                     ufl.And(ufl.ge(x[1], y0), ufl.le(x[1], y1)))
    return ufl.conditional(inside, 1.0, 0.0)
