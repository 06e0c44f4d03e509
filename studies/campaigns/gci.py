"""Richardson extrapolation, observed order and grid convergence index of three solutions.

The procedure of Celik et al. (2008), "Procedure for estimation and reporting of uncertainty due
to discretization in CFD applications", J. Fluids Eng. 130, 078001, on Roache's grid convergence
index (Roache 1994, 1998; ASME V&V 20-2009). With the grid sizes ``h1 < h2 < h3`` (fine to
coarse) and the solutions ``phi1, phi2, phi3``:

* ``r21 = h2 / h1``, ``r32 = h3 / h2``, ``e21 = phi2 - phi1``, ``e32 = phi3 - phi2``,
  ``s = sign(e32 / e21)`` (``s < 0``: oscillatory convergence);
* the observed order ``p`` solves ``p = |ln|e32 / e21| + q(p)| / ln r21`` with
  ``q(p) = ln((r21^p - s) / (r32^p - s))`` (``q = 0`` for a constant ratio), by fixed-point
  iteration from ``q = 0``;
* ``phi_ext = (r21^p phi1 - phi2) / (r21^p - 1)``; the approximate relative error
  ``e_a = |(phi1 - phi2) / phi1|``, the extrapolated relative error
  ``e_ext = |(phi_ext - phi1) / phi_ext|`` and ``GCI_fine = Fs e_a / (r21^p - 1)`` with
  ``Fs = 1.25`` for three grids.

When ``e21 = 0`` or ``e32 = 0`` (two grids agree exactly) the order is undefined: the result
carries ``p = nan`` and says why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: Factor of safety of the GCI with three grids (Roache; Celik et al. 2008).
FS_THREE_GRIDS = 1.25


@dataclass(frozen=True)
class GCIResult:
    """Observed order, extrapolated value and errors of three solutions (fine to coarse)."""

    h: tuple[float, float, float]
    phi: tuple[float, float, float]
    r21: float
    r32: float
    p: float
    phi_ext: float
    e_a21: float
    e_ext21: float
    gci_fine21: float
    oscillatory: bool
    note: str = ""

    @property
    def defined(self) -> bool:
        """Whether an order and an extrapolated value were found."""
        return math.isfinite(self.p)


def _order_equation(p: float, r21: float, r32: float, log_ratio: float, s: float) -> float:
    """``|ln|e32/e21| + q(p)| / ln r21`` (Celik et al. 2008, Eq. 3a); ``nan`` outside its domain."""
    a, b = r21 ** p - s, r32 ** p - s
    if a <= 0.0 or b <= 0.0:
        return math.nan
    return abs(log_ratio + math.log(a / b)) / math.log(r21)


def observed_order(r21: float, r32: float, e21: float, e32: float, tol: float = 1e-14,
                   max_it: int = 1000, p_max: float = 30.0) -> float:
    """The observed order ``p`` of Celik et al. (2008), Eqs. 3a-3c; ``nan`` if none.

    Fixed-point iteration as in the paper; where it does not converge (it contracts only when
    ``r32`` is not much larger than ``r21``), bisection on the same equation over (0, p_max].
    """
    ratio = e32 / e21
    s = math.copysign(1.0, ratio)
    log_ratio = math.log(abs(ratio))
    p = abs(log_ratio) / math.log(r21) or 1.0
    for _ in range(max_it):
        new = _order_equation(p, r21, r32, log_ratio, s)
        if not math.isfinite(new) or new > p_max:
            break
        if abs(new - p) <= tol * max(1.0, abs(new)):
            return new
        p = new

    def g(x: float) -> float:
        return _order_equation(x, r21, r32, log_ratio, s) - x

    grid = [p_max * (k / 600) ** 2 for k in range(1, 601)]
    for lo, hi in zip(grid[:-1], grid[1:], strict=True):
        glo, ghi = g(lo), g(hi)
        if math.isfinite(glo) and math.isfinite(ghi) and glo * ghi <= 0.0:
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if (g(mid) <= 0.0) == (glo <= 0.0):
                    lo, glo = mid, g(mid)
                else:
                    hi = mid
            return 0.5 * (lo + hi)
    return math.nan


def gci(h: tuple[float, float, float], phi: tuple[float, float, float],
        fs: float = FS_THREE_GRIDS) -> GCIResult:
    """Richardson extrapolation and GCI of ``phi`` on grid sizes ``h`` (any order of sizes)."""
    order = sorted(range(3), key=lambda i: h[i])
    (h1, h2, h3), (f1, f2, f3) = [tuple(v[i] for i in order) for v in (h, phi)]
    if not h1 < h2 < h3:
        raise ValueError(f"grid sizes must differ: {h}")
    r21, r32 = h2 / h1, h3 / h2
    e21, e32 = f2 - f1, f3 - f2
    e_a = abs(e21 / f1) if f1 else math.inf
    nan = math.nan
    if e21 == 0.0 or e32 == 0.0:
        return GCIResult((h1, h2, h3), (f1, f2, f3), r21, r32, nan, nan, e_a, nan, nan, False,
                         "two sizes give the same value: order undefined")
    oscillatory = e32 / e21 < 0.0
    p = observed_order(r21, r32, e21, e32)
    if not math.isfinite(p) or p <= 0.0:
        return GCIResult((h1, h2, h3), (f1, f2, f3), r21, r32, nan, nan, e_a, nan, nan,
                         oscillatory, "the order equation has no positive solution")
    rp = r21 ** p
    ext = (rp * f1 - f2) / (rp - 1.0)
    e_ext = abs((ext - f1) / ext) if ext else math.inf
    note = "oscillatory convergence" if oscillatory else "monotonic convergence"
    return GCIResult((h1, h2, h3), (f1, f2, f3), r21, r32, p, ext, e_a, e_ext,
                     fs * e_a / (rp - 1.0), oscillatory, note)


__all__ = ["FS_THREE_GRIDS", "GCIResult", "gci", "observed_order"]
