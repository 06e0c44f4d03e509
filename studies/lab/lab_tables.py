"""The CSV files of ``pilegroup lab``: their names and columns (the data contract) and writer.

``pilegroup fit`` reads the interface and oedometer files with :func:`read_lab_table`, so a lab
output can be fed back. Stresses kPa, slips m, time days; strains dimensionless, compression
positive in the soil tests (the laboratory's sign), as are the interface's normal stresses.

* interface tests, one layout for all four (``interface-shear.csv``, ``interface-creep.csv``,
  ``interface-relaxation.csv``, ``interface-rate.csv``): ``variant,curve,time_day,
  normal_stress_kPa,shear_stress_kPa,slip_m,viscoplastic_slip_m,slip_rate_m_per_day``:
  the Eq. 15 reading (``default`` or ``seed``), the curve's number (one normal stress, held
  shear, held slip or slip rate), the effective normal stress (compression positive), the shear
  stress, the total slip and its viscoplastic part, and the slip rate over the step (the imposed
  rate of the shear tests; the creep rate of a creep test);
* ``triaxial.csv``: ``drainage,curve,confining_stress_kPa,axial_strain,volumetric_strain,
  p_kPa,q_kPa,excess_pore_pressure_kPa`` (``drained`` or ``undrained``; mean effective stress
  p' and deviator q; the excess pore pressure of the undrained test, 0 drained);
* ``oedometer.csv``: ``step,time_day,vertical_strain,vertical_stress_kPa,
  horizontal_stress_kPa,void_ratio`` (the load step's number, 0 the start; the time of the
  reading; loading, the creep stage, unloading; effective stresses).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.fileio import write_text_atomic
from pilegroup.studies.results.tables import Table, read_table

INTERFACE_TESTS = ("interface-shear", "interface-creep", "interface-relaxation", "interface-rate")
SOIL_TESTS = ("triaxial", "oedometer")
#: Every test of ``pilegroup lab``; each writes ``<test>.csv`` and ``<test>.png``.
TESTS = INTERFACE_TESTS + SOIL_TESTS

INTERFACE_COLUMNS = ("variant", "curve", "time_day", "normal_stress_kPa", "shear_stress_kPa",
                     "slip_m", "viscoplastic_slip_m", "slip_rate_m_per_day")
#: Columns of each test's CSV file, in the order they are written.
COLUMNS: dict[str, tuple[str, ...]] = {
    **{t: INTERFACE_COLUMNS for t in INTERFACE_TESTS},
    "triaxial": ("drainage", "curve", "confining_stress_kPa", "axial_strain",
                 "volumetric_strain", "p_kPa", "q_kPa", "excess_pore_pressure_kPa"),
    "oedometer": ("step", "time_day", "vertical_strain", "vertical_stress_kPa",
                  "horizontal_stress_kPa", "void_ratio"),
}
#: The columns that hold text; all others hold numbers.
TEXT_COLUMNS = frozenset({"variant", "drainage"})


def csv_name(test: str) -> str:
    """The file name of a test's table."""
    return f"{test}.csv"


def write_lab_table(path: Path, test: str, table: Table) -> Path:
    """Write ``table`` (column -> values of equal length) with the columns of ``test``."""
    cols = COLUMNS[test]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for i in range(len(table[cols[0]])):
        w.writerow([_cell(table[c][i], c) for c in cols])
    return write_text_atomic(path, buf.getvalue())


def _cell(v: object, column: str) -> str:
    if column in TEXT_COLUMNS:
        return str(v)
    x = float(v)  # type: ignore[arg-type]
    return str(int(x)) if column in ("curve", "step") else f"{x:.10g}"


def read_lab_table(path: Path, required: tuple[str, ...],
                   optional: tuple[str, ...] = ()) -> Table:
    """The ``required`` and present ``optional`` columns of a lab-layout CSV file.

    Besides :func:`~pilegroup.studies.results.tables.read_table`'s checks, a number that is not
    finite (``nan``, ``inf``) is invalid input, named with its column and row.
    """
    table = read_table(path, required, TEXT_COLUMNS, optional)
    for c, vals in table.items():
        if c in TEXT_COLUMNS:
            continue
        bad = np.nonzero(~np.isfinite(vals))[0]
        if bad.size:
            raise ScenarioError(f"{path} row {bad[0] + 2}", "" if np.isnan(vals[bad[0]]) else
                                str(vals[bad[0]]), f"column {c!r} must be a finite number")
    return table


__all__ = ["COLUMNS", "INTERFACE_COLUMNS", "INTERFACE_TESTS", "SOIL_TESTS", "TESTS",
           "csv_name", "read_lab_table", "write_lab_table"]
