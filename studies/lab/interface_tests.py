"""Element tests of the pile-soil interface law at one material point (no mesh).

Each test holds the effective normal stress constant (the normal opening does not change, so
the penalty keeps the initial ``sigma_n``) and drives the slip in one tangential direction with
the law's own ``update`` (backward Euler, :mod:`pilegroup.constitutive.interface_law`):

* **shear** (direct shear at constant normal stress): the slip grows at a constant rate up to
  failure, where the shear reaches the Clough-Duncan strength ``sigma_n tan(delta)`` on the
  elastic hyperbola (the law has no softening, so the test ends there, as a laboratory test
  ends at its peak), or up to ``max_slip`` if that comes first;
* **creep**: the shear is applied at once (no time passes) and then held; the slip needed to hold
  it is found per step by Newton on the law's tangent;
* **relaxation**: the slip that gives the same shear levels is applied at once and then held;
* **rate**: shear to ``max_slip`` at several constant slip rates (the viscoplastic part shows
  where the shear passes the yield surface).

The held shear of creep and relaxation is given as fractions (``levels``) of the hyperbola's
asymptote ``p tan(delta) / R_f`` at the test's normal stress, or in kPa. Every test returns a
table in the layout of :mod:`pilegroup.studies.lab.lab_tables` (one curve per normal stress,
level or rate, per Eq. 15 reading).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pilegroup.constitutive.interface_law import PileSoilInterface
from pilegroup.errors import ConstitutiveError, ScenarioError
from pilegroup.studies.lab.lab_tables import INTERFACE_COLUMNS
from pilegroup.studies.results.tables import Table

#: 1 mm/min in m/day.
MM_PER_MIN = 1.0e-3 * 1440.0
#: Relative tolerance on the held shear of a creep step.
HOLD_TOL = 1.0e-10


def _flag(key: str) -> str:
    """The command-line option of a protocol field."""
    return "--" + key.replace("_", "-")


@dataclass(frozen=True)
class InterfaceProtocol:
    """What the interface tests do (stresses kPa, slips mm, rates mm/min, time days)."""

    normal_stresses_kPa: tuple[float, ...] = (25.0, 50.0, 100.0, 200.0)
    rate_mm_per_min: float = 0.8
    rates_mm_per_min: tuple[float, ...] = (0.0008, 0.008, 0.08, 0.8)
    max_slip_mm: float = 20.0
    levels: tuple[float, ...] = (0.3, 0.5, 0.7, 0.8, 0.9)
    shear_stresses_kPa: tuple[float, ...] = ()
    days: float = 30.0
    steps: int = 60

    def __post_init__(self) -> None:
        for key in ("normal_stresses_kPa", "rates_mm_per_min", "levels"):
            vals = getattr(self, key)
            if not vals or any(not (v > 0.0 and np.isfinite(v)) for v in vals):
                raise ScenarioError(_flag(key), list(vals), "must be one or more numbers > 0")
        if any(not (0.0 < v < 1.0) for v in self.levels):
            raise ScenarioError("--levels", list(self.levels), "must be fractions in (0, 1) of "
                                "the hyperbola's asymptote p tan(delta)/R_f")
        if any(not (v > 0.0 and np.isfinite(v)) for v in self.shear_stresses_kPa):
            raise ScenarioError("--shear-stresses-kPa", list(self.shear_stresses_kPa),
                                "must be numbers > 0")
        for key in ("rate_mm_per_min", "max_slip_mm", "days"):
            v = getattr(self, key)
            if not (v > 0.0 and np.isfinite(v)):
                raise ScenarioError(_flag(key), v, "must be a number > 0")
        if not 2 <= self.steps <= 100_000:
            raise ScenarioError("--steps", self.steps, "must be an integer in [2, 100000]")


class _Rows:
    """The rows of one table, column by column."""

    def __init__(self) -> None:
        self.cols: dict[str, list] = {c: [] for c in INTERFACE_COLUMNS}

    def add(self, variant: str, curve: int, t: float, law_state: Mapping[str, np.ndarray],
            slip: float, rate: float) -> None:
        tr = law_state["traction"][0]
        for c, v in zip(INTERFACE_COLUMNS, (variant, curve, t, -tr[0], tr[1], slip,
                                            law_state["slip_vp"][0, 0], rate), strict=True):
            self.cols[c].append(v)

    def table(self) -> Table:
        return {c: np.array(v, dtype=str if c == "variant" else float)
                for c, v in self.cols.items()}


def _start(law: PileSoilInterface, normal_kPa: float) -> dict[str, np.ndarray]:
    return law.initial_state(1, np.array([-normal_kPa, 0.0, 0.0]))


def _step(law: PileSoilInterface, state: dict[str, np.ndarray], dslip: float, dt: float
          ) -> tuple[dict[str, np.ndarray], float]:
    """One update with slip increment ``dslip`` over ``dt``; the new state and d tau/d slip."""
    _, st, tan = law.update(np.array([[0.0, dslip, 0.0]]), state, dt)
    return st, float(tan[0, 1, 1])


def failure_slip(law: PileSoilInterface, normal_kPa: float) -> float:
    """Slip (m) at which the elastic hyperbola reaches the strength ``p tan(delta)``."""
    a, b = law.hyperbola(np.array([-normal_kPa]))
    tau_f = max(normal_kPa, law.p_floor) * np.tan(np.radians(law.delta))
    return float(a[0] * tau_f / (1.0 - b[0] * tau_f))


def held_shears(law: PileSoilInterface, normal_kPa: float, protocol: InterfaceProtocol
                ) -> tuple[float, ...]:
    """The held shear stresses (kPa) of creep and relaxation at ``normal_kPa``."""
    if protocol.shear_stresses_kPa:
        return protocol.shear_stresses_kPa
    _, b = law.hyperbola(np.array([-normal_kPa]))
    if b[0] <= 0.0:
        raise ScenarioError("--levels", list(protocol.levels), "need R_f > 0 (an asymptote); "
                            "with R_f = 0 give the held shear stresses in kPa")
    return tuple(lev / b[0] for lev in protocol.levels)


def _shear_curve(rows: _Rows, law: PileSoilInterface, curve: int, normal_kPa: float,
                 rate: float, end_slip: float, steps: int) -> None:
    """Slip from 0 to ``end_slip`` (m) at ``rate`` (m/day) in ``steps`` equal steps."""
    st = _start(law, normal_kPa)
    rows.add(law.variant, curve, 0.0, st, 0.0, rate)
    ds = end_slip / steps
    for i in range(1, steps + 1):
        st, _ = _step(law, st, ds, ds / rate)
        rows.add(law.variant, curve, i * ds / rate, st, i * ds, rate)


def shear_test(laws: Mapping[str, PileSoilInterface], protocol: InterfaceProtocol) -> Table:
    """Direct shear at each normal stress, to failure, at ``rate_mm_per_min``."""
    rows = _Rows()
    rate = protocol.rate_mm_per_min * MM_PER_MIN
    for law in laws.values():
        for curve, sn in enumerate(protocol.normal_stresses_kPa, start=1):
            end = min(failure_slip(law, sn), 1e-3 * protocol.max_slip_mm)
            _shear_curve(rows, law, curve, sn, rate, end, protocol.steps)
    return rows.table()


def rate_test(laws: Mapping[str, PileSoilInterface], protocol: InterfaceProtocol) -> Table:
    """Shear to ``max_slip_mm`` at each rate, at the first normal stress."""
    rows = _Rows()
    sn = protocol.normal_stresses_kPa[0]
    for law in laws.values():
        for curve, r in enumerate(protocol.rates_mm_per_min, start=1):
            _shear_curve(rows, law, curve, sn, r * MM_PER_MIN, 1e-3 * protocol.max_slip_mm,
                         protocol.steps)
    return rows.table()


def _hold_shear(law: PileSoilInterface, st: dict[str, np.ndarray], tau: float, dt: float,
                guess: float) -> tuple[dict[str, np.ndarray], float]:
    """The state after ``dt`` with the shear held at ``tau``, and the step's slip."""
    ds = guess
    for _ in range(50):
        new, k = _step(law, st, ds, dt)
        r = new["traction"][0, 1] - tau
        if abs(r) <= HOLD_TOL * max(abs(tau), 1.0):
            return new, ds
        ds -= r / k
    raise ConstitutiveError(f"creep step of {dt:g} day did not hold tau = {tau:g} kPa "
                            "(Newton on the slip did not converge in 50 iterations)")


def _loaded(laws: Mapping[str, PileSoilInterface], protocol: InterfaceProtocol, rows: _Rows
            ) -> Iterator[tuple[PileSoilInterface, int, float, float, dict[str, np.ndarray]]]:
    """Per law, normal stress and held shear: the shear applied at once (no time passes).

    Yields the law, the curve's number, the held shear (kPa), the slip (m) and the state; the
    first row of the curve is written.
    """
    for law in laws.values():
        curve = 0
        for sn in protocol.normal_stresses_kPa:
            for tau in held_shears(law, sn, protocol):
                curve += 1
                a, b = law.hyperbola(np.array([-sn]))
                w = float(a[0] * tau / (1.0 - b[0] * tau))
                st, _ = _step(law, _start(law, sn), w, 0.0)
                rows.add(law.variant, curve, 0.0, st, w, 0.0)
                yield law, curve, tau, w, st


def creep_test(laws: Mapping[str, PileSoilInterface], protocol: InterfaceProtocol) -> Table:
    """Each held shear applied at once, then held for ``days`` in ``steps`` equal steps."""
    rows = _Rows()
    dt = protocol.days / protocol.steps
    for law, curve, tau, w, st in _loaded(laws, protocol, rows):
        ds = 0.0
        for i in range(1, protocol.steps + 1):
            st, ds = _hold_shear(law, st, tau, dt, ds)
            w += ds
            rows.add(law.variant, curve, i * dt, st, w, ds / dt)
    return rows.table()


def relaxation_times(days: float, steps: int) -> np.ndarray:
    """Output times of a relaxation test: 0, then ``steps`` geometric times to ``days``."""
    return np.concatenate([[0.0], np.geomspace(days * 1e-4, days, steps)])


def relaxation_test(laws: Mapping[str, PileSoilInterface], protocol: InterfaceProtocol
                    ) -> Table:
    """The slip of each shear level applied at once, then held for ``days``."""
    rows = _Rows()
    times = relaxation_times(protocol.days, protocol.steps)
    zero = np.zeros((1, 3))
    for law, curve, _, w, st in _loaded(laws, protocol, rows):
        for t0, t1 in zip(times[:-1], times[1:], strict=True):
            _, st, _ = law.update(zero, st, t1 - t0)
            rows.add(law.variant, curve, t1, st, w, 0.0)
    return rows.table()


#: Test name -> function of the interface laws (per variant) and the protocol.
INTERFACE_RUNNERS = {"interface-shear": shear_test, "interface-creep": creep_test,
                     "interface-relaxation": relaxation_test, "interface-rate": rate_test}


def run_interface_test(test: str, laws: Mapping[str, PileSoilInterface],
                       protocol: InterfaceProtocol, variants: Sequence[str] | None = None
                       ) -> Table:
    """The table of interface test ``test`` for the given readings of Eq. 15."""
    chosen = {v: laws[v] for v in (variants or laws)}
    return INTERFACE_RUNNERS[test](chosen, protocol)


__all__ = ["INTERFACE_RUNNERS", "InterfaceProtocol", "MM_PER_MIN", "creep_test",
           "failure_slip", "held_shears", "rate_test", "relaxation_test", "relaxation_times",
           "run_interface_test", "shear_test"]
