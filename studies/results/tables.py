"""The CSV files of a run folder: their names and columns (the data contract) and a reader.

The writers take their header lines from here and the report reads the files with
:func:`read_csv`, so both sides use one list of columns. Depths in m below the ground surface,
positive down; forces kN; stresses kPa; displacements m.

* ``settlement.csv``: ``t_day,stage,settlement_m`` (cap settlement, down positive);
* ``pile_profiles.csv``: ``t_day,pile,depth_m,layer,axial_force_kN,shaft_friction_kPa,
  relative_displacement_m`` (axial force compression positive; friction positive = the soil
  supports the pile; relative displacement = pile minus adjacent soil settlement, positive = the
  pile moves down relative to the soil);
* ``layer_history.csv``: ``t_day,pile,layer,layer_name,depth_top_m,depth_bottom_m,
  shaft_friction_kPa,relative_displacement_m,viscoplastic_slip_m,normal_traction_kPa`` (layer
  means on the shaft of the centre pile, every accepted step);
* ``interface_layers.csv``: the columns of ``layer_history.csv``, every pile at the output
  times; a layer's ``depth_bottom_m`` is the pile's toe where the pile ends in it (a layer mean
  times the pile's perimeter and the layer's thickness is then the layer's shaft force);
* ``pile_loads.csv``: ``t_day,pile,x_m,y_m,head_force_kN,depth_m``: each pile's head force
  due to the loads, the same number as ``pile_heads.csv``'s ``N_kN`` (``depth_m`` 0, the head).
  The axial force below the head, read as a strain gauge reads it, is ``pile_profiles.csv``'s
  (docs/model.md, "Which head force");
* ``load_settlement.csv``: ``t_day,stage,load_factor,load_kN,settlement_m`` (every accepted
  step: the load–settlement curve, also of a run that found no equilibrium beyond some load);
* ``gauges.csv``: ``time_day,pile,section,depth_m,strain,N_kN,f_kPa,w_mm`` (the virtual strain
  gauges reduced by the paper's field method, :mod:`pilegroup.studies.results.gauges`: section-mean
  axial strain, compression positive; axial force; friction of the interval from the section
  down to the next one, NaN at the last section; relative displacement, mm), then the model's
  own values at the same sections ``N_model_kN,f_model_kPa,w_model_mm`` (axial force from the
  pile stress, interface shear averaged over the same interval, pile minus adjacent soil
  displacement), ``w_pile_mm`` (the model's pile settlement there) and the errors of the field
  method, field minus model: ``N_error_kN,f_error_kPa,w_error_mm``; every pile, every output
  time;
* ``neutral_plane.csv``: ``t_day,pile,neutral_plane_depth_m,dragload_kN,downdrag_m,
  head_load_kN,max_axial_force_kN,head_settlement_m`` (:mod:`pilegroup.studies.results.downdrag`);
* ``settlement_profiles.csv``: ``t_day,pile,depth_m,axial_force_kN,pile_settlement_m,
  soil_settlement_m,excess_pore_pressure_kPa`` (per pile at its element layers: the soil beside
  the pile, the excess pore pressure at the shaft; ``pile = 0``: the free field, axial force
  and pile settlement empty);
* ``surface_trough.csv``: ``t_day,x_m,settlement_m`` (the ground surface through the group's
  centre, parallel to x);
* ``capacity.csv`` (runs with a capacity stage): ``t_day,pile,load_factor,load_kN,settlement_m,
  tangent_stiffness_kN_per_m``: the load–settlement curve of the capacity stage, starting from
  the state before it; ``pile = 0`` is the group (the cap load and the cap settlement, or the
  load on every pile head and their mean settlement without a cap), ``pile = i`` pile ``i``
  (its head force due to the loads, from its top element layer, and its settlement there);
  the tangent stiffness of the segment ending at the row (empty at the first row and where the
  settlement did not grow). The criteria read off it are in ``summary.json``
  (:mod:`pilegroup.studies.results.capacity`);
* ``cap_motion.csv``: ``t_day,ux_m,uy_m,uz_m,rx_rad,ry_rad,rz_rad``: the cap's (or the single
  pile head's) rigid motion at the scenario's action point, global axes, z up (a settlement is
  a negative ``uz_m``);
* ``pile_heads.csv``: ``t_day,pile,x_m,y_m,N_kN,Vx_kN,Vy_kN,Mx_kNm,My_kNm,T_kNm,depth_m``: the
  cap's action on each pile at its head (the load on a head without a cap; axial force
  compression positive; shears, moments and torque in global axes about the head centre);
  ``depth_m`` 0: the first row of the pile's ``pile_bending.csv``;
* ``pile_bending.csv``: ``t_day,pile,depth_m,N_kN,Vx_kN,Vy_kN,Mx_kNm,My_kNm,T_kNm,ux_m,uy_m``:
  section actions (the part above on the part below) and the pile axis's deflection at the head
  (depth 0) and at every element-layer boundary down to the toe;
* ``pile_max_moment.csv``: ``t_day,pile,M_max_kNm,depth_m``: the largest resultant bending
  moment ``sqrt(Mx^2 + My^2)`` of each pile's ``pile_bending.csv`` rows and its depth;
* ``cap_stiffness.csv`` (runs with ``outputs.cap_stiffness``): ``action,ux_m,uy_m,uz_m,rx_rad,
  ry_rad,rz_rad``: rows ``Fx`` .. ``Mz`` of the cap's 6 x 6 stiffness matrix about the action
  point, ``K[i, j] = dF_i / du_j`` (:mod:`pilegroup.studies.run.stiffness`).

The conventions of ``pile_heads.csv``, ``pile_bending.csv`` and ``pile_max_moment.csv`` are those
of :mod:`pilegroup.studies.run.section_probe`; every force and moment is the change since the
geostatic state.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from pilegroup.model import ScenarioError

SETTLEMENT_CSV = "settlement.csv"
PROFILES_CSV = "pile_profiles.csv"
LAYER_HISTORY_CSV = "layer_history.csv"
INTERFACE_LAYERS_CSV = "interface_layers.csv"
LOADS_CSV = "pile_loads.csv"
LOAD_SETTLEMENT_CSV = "load_settlement.csv"
GAUGES_CSV = "gauges.csv"
NEUTRAL_PLANE_CSV = "neutral_plane.csv"
SETTLEMENT_PROFILES_CSV = "settlement_profiles.csv"
TROUGH_CSV = "surface_trough.csv"
CAPACITY_CSV = "capacity.csv"
CAP_MOTION_CSV = "cap_motion.csv"
HEADS_CSV = "pile_heads.csv"
BENDING_CSV = "pile_bending.csv"
MAX_MOMENT_CSV = "pile_max_moment.csv"
STIFFNESS_CSV = "cap_stiffness.csv"

_LAYER_MEANS = ("t_day", "pile", "layer", "layer_name", "depth_top_m", "depth_bottom_m",
                "shaft_friction_kPa", "relative_displacement_m", "viscoplastic_slip_m",
                "normal_traction_kPa")

#: Columns of each CSV file, in the order the writers write them (a reader ignores extra ones).
COLUMNS: dict[str, tuple[str, ...]] = {
    SETTLEMENT_CSV: ("t_day", "stage", "settlement_m"),
    PROFILES_CSV: ("t_day", "pile", "depth_m", "layer", "axial_force_kN", "shaft_friction_kPa",
                   "relative_displacement_m"),
    LAYER_HISTORY_CSV: _LAYER_MEANS,
    INTERFACE_LAYERS_CSV: _LAYER_MEANS,
    LOADS_CSV: ("t_day", "pile", "x_m", "y_m", "head_force_kN"),
    LOAD_SETTLEMENT_CSV: ("t_day", "stage", "load_factor", "load_kN", "settlement_m"),
    GAUGES_CSV: ("time_day", "pile", "section", "depth_m", "strain", "N_kN", "f_kPa", "w_mm",
                 "N_model_kN", "f_model_kPa", "w_model_mm", "w_pile_mm", "N_error_kN",
                 "f_error_kPa", "w_error_mm"),
    NEUTRAL_PLANE_CSV: ("t_day", "pile", "neutral_plane_depth_m", "dragload_kN", "downdrag_m",
                        "head_load_kN", "max_axial_force_kN", "head_settlement_m"),
    SETTLEMENT_PROFILES_CSV: ("t_day", "pile", "depth_m", "axial_force_kN", "pile_settlement_m",
                              "soil_settlement_m", "excess_pore_pressure_kPa"),
    TROUGH_CSV: ("t_day", "x_m", "settlement_m"),
    CAPACITY_CSV: ("t_day", "pile", "load_factor", "load_kN", "settlement_m",
                   "tangent_stiffness_kN_per_m"),
    CAP_MOTION_CSV: ("t_day", "ux_m", "uy_m", "uz_m", "rx_rad", "ry_rad", "rz_rad"),
    HEADS_CSV: ("t_day", "pile", "x_m", "y_m", "N_kN", "Vx_kN", "Vy_kN", "Mx_kNm", "My_kNm",
                "T_kNm", "depth_m"),
    BENDING_CSV: ("t_day", "pile", "depth_m", "N_kN", "Vx_kN", "Vy_kN", "Mx_kNm", "My_kNm",
                  "T_kNm", "ux_m", "uy_m"),
    MAX_MOMENT_CSV: ("t_day", "pile", "M_max_kNm", "depth_m"),
    STIFFNESS_CSV: ("action", "ux_m", "uy_m", "uz_m", "rx_rad", "ry_rad", "rz_rad"),
}
#: Columns added to a file after its contract was set: written after :data:`COLUMNS`, read
#: where present (an older run folder lacks them).
ADDED: dict[str, tuple[str, ...]] = {LOADS_CSV: ("depth_m",)}
#: The columns that hold text; all others hold numbers.
TEXT_COLUMNS = frozenset({"stage", "layer_name", "action"})

#: Header lines of the writers.
SETTLEMENT_COLUMNS = ",".join(COLUMNS[SETTLEMENT_CSV])
PROFILE_COLUMNS = ",".join(COLUMNS[PROFILES_CSV])
LAYER_COLUMNS = ",".join(_LAYER_MEANS)
LOAD_COLUMNS = ",".join(COLUMNS[LOADS_CSV] + ADDED[LOADS_CSV])
LOAD_SETTLEMENT_COLUMNS = ",".join(COLUMNS[LOAD_SETTLEMENT_CSV])
GAUGE_COLUMNS = ",".join(COLUMNS[GAUGES_CSV])
NEUTRAL_PLANE_COLUMNS = ",".join(COLUMNS[NEUTRAL_PLANE_CSV])
SETTLEMENT_PROFILE_COLUMNS = ",".join(COLUMNS[SETTLEMENT_PROFILES_CSV])
TROUGH_COLUMNS = ",".join(COLUMNS[TROUGH_CSV])
CAPACITY_COLUMNS = ",".join(COLUMNS[CAPACITY_CSV])
CAP_MOTION_COLUMNS = ",".join(COLUMNS[CAP_MOTION_CSV])
HEAD_COLUMNS = ",".join(COLUMNS[HEADS_CSV])
BENDING_COLUMNS = ",".join(COLUMNS[BENDING_CSV])
MAX_MOMENT_COLUMNS = ",".join(COLUMNS[MAX_MOMENT_CSV])
STIFFNESS_COLUMNS = ",".join(COLUMNS[STIFFNESS_CSV])
#: The value columns of ``gauges.csv`` (after time, pile, section and depth).
GAUGE_VALUES = COLUMNS[GAUGES_CSV][4:]

#: A CSV file read by :func:`read_csv`: column name -> values (float, or str for text columns).
Table = dict[str, np.ndarray]


def _columns_error(path: Path, header: list[str], problem: str,
                   columns: tuple[str, ...]) -> ScenarioError:
    required = ", ".join(columns)
    return ScenarioError(f"{path} header", ",".join(header),
                         f"{problem}; required columns: {required}")


def read_csv(path: Path) -> Table | None:
    """Columns of a contract CSV as arrays (text or float); ``None`` if the file does not exist.

    The file name selects the columns (:data:`COLUMNS`, and those of :data:`ADDED` present).
    Raises :class:`ScenarioError` for an empty file, a missing column, a short row or a
    non-numeric value, naming the file, the column and the columns required. An empty cell is
    a quantity that does not exist there (e.g. the friction below the last gauge section): NaN
    in the array; no file holds the text "nan".
    """
    if not path.is_file():
        return None
    return read_table(path, COLUMNS[path.name], TEXT_COLUMNS, ADDED.get(path.name, ()))


def read_table(path: Path, columns: tuple[str, ...], text: frozenset[str] = frozenset(),
               optional: tuple[str, ...] = ()) -> Table:
    """The ``columns`` (all required) and those of ``optional`` present in the CSV ``path``.

    Columns in ``text`` are read as strings, the others as numbers (an empty cell is NaN). A
    missing file, a missing column, a short row or a non-numeric value is a
    :class:`ScenarioError` naming the file, the row, the column and the value.
    """
    if not path.is_file():
        raise ScenarioError("file", str(path), "no such file")
    try:
        with path.open(newline="", encoding="utf-8") as fh:
            rows = [r for r in csv.reader(fh) if any(x.strip() for x in r)]
    except (UnicodeDecodeError, csv.Error) as exc:
        raise ScenarioError("file", str(path), f"is not a UTF-8 CSV file ({exc})") from None
    header = [h.strip() for h in rows[0]] if rows else []
    if not header:
        raise _columns_error(path, header, "no header row", columns)
    missing = [c for c in columns if c not in header]
    if missing:
        raise _columns_error(path, header, f"missing column {missing[0]!r}", columns)
    body = rows[1:]
    for n, row in enumerate(body, start=2):
        if len(row) < len(header):
            raise ScenarioError(f"{path} row {n}", ",".join(row),
                                f"{len(row)} fields, the header has {len(header)}")
    table: Table = {}
    for c in (*columns, *(o for o in optional if o in header)):
        i = header.index(c)
        if c in text:
            table[c] = np.array([r[i].strip() for r in body], dtype=str)
            continue
        vals = np.empty(len(body))
        for n, row in enumerate(body, start=2):
            try:
                vals[n - 2] = float(row[i]) if row[i].strip() else np.nan
            except ValueError:
                raise ScenarioError(f"{path} row {n}", row[i].strip(),
                                    f"column {c!r} must be a number") from None
        table[c] = vals
    return table
