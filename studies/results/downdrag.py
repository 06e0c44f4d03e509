"""The unified method's reading of a pile's profiles: neutral plane, dragload and downdrag.

Pure functions of the profiles (numpy). Conventions: depth m below the ground surface, positive
down, stations from the head to the toe; axial force kN, compression positive, the force due to
the loads (head load at the first station); settlements m, down positive.

Fellenius' unified method (Fellenius 2004, "Unified design of piled foundations with emphasis
on settlement analysis", ASCE GSP 125; NCHRP Report 1112, 2024): above the neutral plane the
soil settles more than the pile and loads it by negative skin friction, below it the pile
settles more and the friction is positive. The neutral plane is where the axial force is
largest (force equilibrium) and, ideally, where pile and soil settle alike (settlement
equilibrium). The dragload is the largest axial force minus the head load; the downdrag the
pile's settlement at the neutral plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class NeutralPlane:
    """One pile's neutral plane at one time (units in the names)."""

    depth_m: float
    """Depth of the largest axial force, m (the head's station when the force only decreases)."""
    dragload_kN: float
    """Largest axial force minus the head load, kN (>= 0)."""
    downdrag_m: float
    """The pile's settlement at the neutral plane, m."""
    head_load_kN: float
    """The axial force at the head's station, kN."""
    max_force_kN: float
    """The largest axial force, kN."""
    equal_settlement_depth_m: float
    """Where the pile's and the soil's settlements are equal (first crossing from the soil
    settling more to the pile settling more), m; NaN when they do not cross."""


def _vertex(z: np.ndarray, f: np.ndarray, k: int) -> tuple[float, float]:
    """Depth and value of the largest ``f`` near station ``k`` (parabola through k-1, k, k+1).

    The parabola makes the neutral plane independent of where the stations fall (it moves
    continuously with the profile); at the first or last station the station itself is used.
    """
    if k == 0 or k == len(z) - 1:
        return float(z[k]), float(f[k])
    z0, z1, z2 = z[k - 1:k + 2]
    f0, f1, f2 = f[k - 1:k + 2]
    A = np.array([[z0**2, z0, 1.0], [z1**2, z1, 1.0], [z2**2, z2, 1.0]])
    a, b, c = np.linalg.solve(A, np.array([f0, f1, f2]))
    if a >= 0.0:  # not a maximum (flat): keep the station
        return float(z1), float(f1)
    zv = float(np.clip(-b / (2 * a), z0, z2))
    return zv, float(a * zv**2 + b * zv + c)


def neutral_plane(depth: np.ndarray, force: np.ndarray, pile_settlement: np.ndarray,
                  soil_settlement: np.ndarray) -> NeutralPlane:
    """The neutral plane of a pile from its profiles at the same stations (module doc)."""
    z = np.asarray(depth, dtype=float)
    N = np.asarray(force, dtype=float)
    sp = np.asarray(pile_settlement, dtype=float)
    ss = np.asarray(soil_settlement, dtype=float)
    k = int(np.argmax(N))
    zn, nmax = _vertex(z, N, k)
    head = float(N[0])
    d = sp - ss
    cross = np.nonzero((d[:-1] < 0.0) & (d[1:] >= 0.0))[0]
    if cross.size:
        j = int(cross[0])
        ze = float(z[j] + (z[j + 1] - z[j]) * (-d[j]) / (d[j + 1] - d[j]))
    else:
        ze = float("nan")
    return NeutralPlane(depth_m=zn, dragload_kN=max(nmax - head, 0.0),
                        downdrag_m=float(np.interp(zn, z, sp)), head_load_kN=head,
                        max_force_kN=nmax, equal_settlement_depth_m=ze)
