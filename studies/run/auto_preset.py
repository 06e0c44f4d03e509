"""What ``numerics.solver.preset = "auto"`` stands for: the fastest preset measured per system.

The table :data:`AUTO_TABLE` holds, per kind of system (the model part the symmetry leaves, the
piles joined by the interface or tied, the size in unknowns), the preset that finished the
bundled Pier 667 job fastest in whole runs on this project's reference machine (2 cores,
``mpirun -n 2``; docs/benchmarks.md, "The preset `auto` picks"). The first row that matches
wins. ``pilegroup bench presets`` runs the job with each candidate preset per size and model
and prints the table this module should hold (:func:`table_source`), so the choice is
regenerated from measurements, not edited by hand.

A preset that fails during a run still hands over to its fallback with one warning line
(``solver.presets.Preset.fallback``).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from pilegroup.errors import SolverInputError
from pilegroup.model import Scenario
from pilegroup.solver.presets import check_available, get_preset, missing_packages


@dataclass(frozen=True)
class AutoRow:
    """One row of the table behind ``auto``.

    Attributes:
        model: the model part (``"quarter"``, ``"half"``, ``"none"``) or ``"*"`` (any).
        interface: ``True``: piles joined to the soil by the interface (a body of their own);
            ``False``: tied piles; ``None``: either.
        max_dofs: the row holds for systems up to this many unknowns (``None``: any size).
        preset: the preset chosen.
        measured: what the choice rests on (sizes, presets and wall times compared).
    """

    model: str
    interface: bool | None
    max_dofs: int | None
    preset: str
    measured: str = ""

    def matches(self, model: str, interface: bool, dofs: int) -> bool:
        """Whether a system of ``dofs`` unknowns of this model and interface is this row's."""
        return ((self.model in ("*", model))
                and (self.interface is None or self.interface == interface)
                and (self.max_dofs is None or dofs <= self.max_dofs))


#: Small systems: one MUMPS factorisation per Newton matrix (``direct``) is cheapest and
#: simplest; the benchmark keeps this row first.
SMALL_ROW = AutoRow("*", None, 50_000, "direct",
                    "small systems: one MUMPS factorisation per Newton matrix")

#: What no measured row covers: the kept LU, the fallback of every iterative preset.
FALLBACK_ROW = AutoRow("*", None, None, "direct_reuse", "not measured: the kept LU")

#: The measured choice, first match wins (docs/benchmarks.md, "The preset `auto` picks").
AUTO_TABLE: tuple[AutoRow, ...] = (
    SMALL_ROW,
    AutoRow("none", True, None, "direct_reuse",
            "none, 301,772 unknowns: direct_reuse 238 s, fieldsplit_kept 747 s, "
            "fieldsplit_pier 833 s"),
    AutoRow("quarter", True, None, "direct_reuse",
            "quarter, 80,853 unknowns: direct_reuse 47 s, fieldsplit_kept 165 s"),
    FALLBACK_ROW,
)


def auto_preset(dofs: int, model: str = "*", interface: bool = True,
                table: Iterable[AutoRow] = AUTO_TABLE) -> str:
    """The preset ``auto`` stands for, from the first row of ``table`` that matches.

    A system of ``dofs`` unknowns, model part ``model``, piles joined by the interface
    (``interface``) or tied. Rows whose preset this PETSc cannot run (the hypre preset where
    PETSc has no hypre) are passed over.
    """
    for row in table:
        if row.matches(model, interface, dofs) and not missing_packages(row.preset):
            return row.preset
    raise SolverInputError(f"no preset in the auto table for {dofs} unknowns, model {model!r},"
                           f" interface {interface}")


def scenario_preset(sc: Scenario, model: str, dofs: int, asked: str | None = None) -> str:
    """The preset a run of ``sc`` uses: ``asked`` (or the scenario's), ``auto`` resolved.

    ``model``: the model part the run holds (``ResolvedGeometry.symmetry``); ``dofs``: its
    unknowns (counted on the mesh, or estimated before meshing). A preset named that this
    PETSc cannot run is refused (:class:`~pilegroup.errors.PresetUnavailable`, one line).
    """
    preset = asked or sc.numerics.solver.preset
    if preset != "auto":
        check_available(preset)
        return preset
    return auto_preset(dofs, model, sc.interface.mode != "tied")


def fastest_rows(results: Iterable[Mapping[str, Any]]) -> list[AutoRow]:
    """Rows of the table from benchmark results.

    Per (model, interface) and measured size, the preset of the shortest complete run, up to
    that size's unknowns; the largest size's row holds for any larger system, and neighbouring
    rows with the same preset are merged. Where a preset that needs an external package
    (``Preset.requires``: hypre) is chosen anywhere, the rows of the runs of the other presets
    follow: a PETSc without that package passes over its rows (:func:`auto_preset`) to them.

    ``results``: rows of ``pilegroup bench presets`` (``symmetry``, ``interface``, ``dofs``,
    ``preset``, ``status``, ``wall_s``).
    """
    done = [r for r in results if r.get("status") == "complete"]
    rows = _fastest(done)
    if any(get_preset(r.preset).requires for r in rows):
        rows += _fastest([r for r in done if not get_preset(str(r["preset"])).requires])
    return rows


def _fastest(done: Iterable[Mapping[str, Any]]) -> list[AutoRow]:
    """:func:`fastest_rows` of complete runs ``done``, without the rows for other PETSc."""
    groups: dict[tuple[str, bool], dict[int, list[Mapping[str, Any]]]] = {}
    for r in done:
        sizes = groups.setdefault((str(r["symmetry"]), bool(r["interface"])), {})
        sizes.setdefault(int(r["dofs"]), []).append(r)
    rows: list[AutoRow] = []
    for (model, itf), sizes in sorted(groups.items()):
        mine: list[AutoRow] = []
        for dofs in sorted(sizes):
            runs = sorted(sizes[dofs], key=lambda r: r["wall_s"])
            said = ", ".join(f"{r['preset']} {r['wall_s']:.0f} s" for r in runs)
            note = f"{model}, {dofs:,} unknowns: {said}"
            if mine and mine[-1].preset == runs[0]["preset"]:
                note = f"{mine.pop().measured}; {note}"
            mine.append(AutoRow(model, itf, dofs, str(runs[0]["preset"]), note))
        last = mine.pop()
        rows += [*mine, AutoRow(last.model, last.interface, None, last.preset, last.measured)]
    return rows


def _q(text: str) -> str:
    """``text`` as a double-quoted Python string literal (the project's style)."""
    return json.dumps(text, ensure_ascii=False)


def table_source(rows: Iterable[AutoRow]) -> str:
    """The Python source of ``AUTO_TABLE`` for the measured ``rows`` (the benchmark prints it).

    The rows stand between :data:`SMALL_ROW` and :data:`FALLBACK_ROW`.
    """
    lines = ["AUTO_TABLE: tuple[AutoRow, ...] = (", "    SMALL_ROW,"]
    for r in rows:
        lines.append(f"    AutoRow({_q(r.model)}, {r.interface!r}, {r.max_dofs!r}, {_q(r.preset)},")
        lines.append(f"            {_q(r.measured)}),")
    lines += ["    FALLBACK_ROW,", ")"]
    return "\n".join(lines)
