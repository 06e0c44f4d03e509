"""What a least-squares fit found: values, standard errors and correlations, as one record.

Standard errors come from the Jacobian ``J`` of the residuals at the solution (the linearised
model): ``cov = s^2 (J^T J)^-1`` with ``s^2 = SSR / (m - p)`` (m residuals, p parameters), the
correlations from ``cov``. The columns of ``J`` are scaled to unit length first, so that a
parameter the residuals do not depend on (a zero or dependent column) is found by the
condition number, whatever the units, and named in a :class:`~pilegroup.errors.FitError`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import OptimizeResult

from pilegroup.errors import FitError

#: Smallest singular value of the column-scaled Jacobian, relative to the largest, of a fit
#: whose parameters the data determine.
MIN_CONDITION = 1e-8


@dataclass(frozen=True)
class FitResult:
    """A fit's parameters (scenario key names, their units) and how well the data fix them."""

    fit: str
    data: str
    names: tuple[str, ...]
    values: tuple[float, ...]
    standard_errors: tuple[float, ...]
    correlations: tuple[tuple[float, ...], ...]
    misfit: float
    """Root mean square of the residuals, in ``misfit_unit``."""
    misfit_unit: str
    points: int
    evaluations: int
    details: tuple[tuple[str, Any], ...] = ()

    def value(self, name: str) -> float:
        """The fitted value of ``name``."""
        return self.values[self.names.index(name)]

    def as_json(self) -> dict[str, Any]:
        """The record of ``--json``: the fitted values under their key names, then the rest."""
        out: dict[str, Any] = dict(zip(self.names, self.values, strict=True))
        out["standard_errors"] = dict(zip(self.names, self.standard_errors, strict=True))
        out["correlations"] = {a: dict(zip(self.names, row, strict=True))
                               for a, row in zip(self.names, self.correlations, strict=True)}
        out.update(fit=self.fit, data=self.data, misfit=self.misfit,
                   misfit_unit=self.misfit_unit, points=self.points,
                   evaluations=self.evaluations, **dict(self.details))
        return json.loads(json.dumps(out, default=str))

    def text(self) -> str:
        """Lines for a terminal: value +- standard error per key, correlations, misfit."""
        lines = [f"{self.fit}: {self.data}"]
        for n, v, e in zip(self.names, self.values, self.standard_errors, strict=True):
            lines.append(f"  {n} = {v:.6g} +- {e:.3g}")
        if len(self.names) > 1:
            lines.append("  correlations: " + ", ".join(
                f"{a}/{b} {self.correlations[i][j]:+.3f}" for i, a in enumerate(self.names)
                for j, b in enumerate(self.names) if j > i))
        lines.append(f"  misfit (rms) = {self.misfit:.4g} {self.misfit_unit} over "
                     f"{self.points} points, {self.evaluations} evaluations")
        lines += [f"  {k}: {v}" for k, v in self.details if not isinstance(v, list | dict)]
        return "\n".join(lines)


def covariance(jac: np.ndarray, residual: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """``s^2 (J^T J)^-1``; a :class:`FitError` naming the parameter the data do not determine."""
    m, p = jac.shape
    norms = np.linalg.norm(jac, axis=0)
    if np.any(norms == 0.0):
        raise FitError(f"the data do not determine {names[int(np.argmin(norms))]}: the "
                       "residuals do not change with it")
    js = jac / norms
    u, sv, vt = np.linalg.svd(js, full_matrices=False)
    if sv[-1] < MIN_CONDITION * sv[0]:
        worst = names[int(np.argmax(np.abs(vt[-1])))]
        raise FitError(f"the data do not determine {worst}: it trades off against the other "
                       f"parameters (condition {sv[0] / sv[-1]:.3g})")
    s2 = float(residual @ residual) / max(m - p, 1)
    inv = (vt.T / sv**2) @ vt
    return s2 * inv / np.outer(norms, norms)


def statistics(jac: np.ndarray, residual: np.ndarray, names: Sequence[str], report: int,
               scale: Sequence[float] | None = None) -> tuple[tuple[float, ...],
                                                            tuple[tuple[float, ...], ...]]:
    """Standard errors and correlations of the first ``report`` parameters.

    ``scale``: factors from the fitted parameters to the reported ones (e.g. 1e-3 from
    kPa·day/m to MPa·day/m); the correlations do not depend on them.
    """
    cov = covariance(jac, residual, names)[:report, :report]
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    corr = cov / np.outer(np.where(se > 0, se, 1.0), np.where(se > 0, se, 1.0))
    factors = np.ones(report) if scale is None else np.asarray(scale, dtype=float)
    return (tuple(float(x) for x in se * factors),
            tuple(tuple(float(x) for x in row) for row in corr))


def check_converged(res: OptimizeResult, names: Sequence[str], lo: Sequence[float],
                    hi: Sequence[float], data: str) -> None:
    """A :class:`FitError` if the solver stopped early or a parameter ended on its bound."""
    if res.status <= 0:
        raise FitError(f"fit to {data} did not converge in {res.nfev} evaluations: "
                       f"{res.message}")
    for i, n in enumerate(names):
        if res.active_mask[i] != 0:
            raise FitError(f"fit to {data}: {n} = {res.x[i]:.6g} ended on its bound "
                           f"[{lo[i]:g}, {hi[i]:g}]: the data do not determine it there")


def rms(residual: np.ndarray) -> float:
    """Root mean square of ``residual``."""
    return math.sqrt(float(np.mean(residual**2))) if residual.size else 0.0


__all__ = ["FitResult", "MIN_CONDITION", "check_converged", "covariance", "rms", "statistics"]
