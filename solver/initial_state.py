"""The soil's state at the start and at the structure's installation (docs/model.md).

:class:`InitialState` puts the geostatic effective stress (:class:`SoilColumn`) into the soil's
quadrature states and the excess pore pressure at the start (consolidating layers, the piles'
installation) into the pressure field; a structure installed after the start
(``BiotProblem(install_later=True)``) adds the installation's excess pore pressure when it is
installed. The installation's share of the effective stress is the pressure element's
interpolant at the quadrature points, so that it balances the pressure field exactly.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from dolfinx import fem

from pilegroup.solver.geostatic import SoilColumn
from pilegroup.solver.inputs import InstallationExcess, SoilMaterial
from pilegroup.solver.layout import BlockLayout, Body


class InitialState:
    """Initial stresses and pressures of the soil (see the module doc).

    Args:
        column: the soil layers (its ``installation`` is the one in force now).
        layout: spaces and fields.
        installation: the installation's excess pore pressure.
        install_later: the installation happens at :meth:`install`, not at the start.
    """

    def __init__(self, column: SoilColumn, layout: BlockLayout,
                 installation: InstallationExcess | None, install_later: bool) -> None:
        self.column, self.layout = column, layout
        self.installation = installation
        column.installation = None if install_later else installation

    def effective_stress(self, bodies: Sequence[Body]) -> dict[str, np.ndarray]:
        """K0 effective stress (less the installation's pressure) per group (Mandel, kPa)."""
        return self.column.stress([b.qp for b in bodies], self._at_points(bodies))

    def _at_points(self, bodies: Sequence[Body]) -> dict[str, np.ndarray] | None:
        """The installation excess pore pressure at every soil group's quadrature points."""
        if self.column.installation is None:
            return None
        out = {}
        for b in bodies:
            soil = [g for g in b.qp.groups if isinstance(g.material, SoilMaterial)]
            if not soil:
                continue
            f = fem.Function(fem.functionspace(b.mesh, self.layout.Q.ufl_element()))
            f.interpolate(lambda x: self.column.installation_excess(x.T))
            expr = fem.Expression(f, b.qp.points)
            for g in soil:
                out[g.name] = expr.eval(b.mesh, g.cells).reshape(-1) if g.n else np.zeros(0)
        return out

    @property
    def has_excess(self) -> bool:
        """Whether the soil starts with an excess pore pressure (layers, installation)."""
        return self.column.has_excess or self.column.installation is not None

    def set_pressure(self) -> None:
        """The excess pore pressure at the start: the layers' ``u0`` plus the installation's."""
        lay = self.layout
        x = lay.Q.tabulate_dof_coordinates()
        for f in (lay.p, lay.p_n):
            f.x.array[:] = self.column.excess(x[:, 2])
            if self.column.installation is not None:
                f.x.array[:] += self.column.installation_excess(x)

    def install(self, bodies: Sequence[Body], restored: bool) -> None:
        """Add the installation's excess pore pressure now, the total stress held.

        The soil's effective stress loses it in every direction and the pressure field gains
        it (committed and current); the interface's share is the caller's
        (``column.installation_excess``). ``restored``: the state is a checkpoint's, taken
        after the installation, which holds it already.
        """
        self.column.installation = self.installation
        if self.installation is None or restored:
            return
        at_points = self._at_points(bodies) or {}
        for b in bodies:
            b.qp.add_isotropic_stress(at_points)
        lay = self.layout
        x = lay.Q.tabulate_dof_coordinates()
        for f in (lay.p, lay.p_n):
            f.x.array[:] += self.column.installation_excess(x)


__all__ = ["InitialState"]
