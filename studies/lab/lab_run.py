"""One ``pilegroup lab`` test run at a material point: ``<test>.csv`` and ``<test>.png``."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pilegroup.studies.lab.interface_tests import InterfaceProtocol, run_interface_test
from pilegroup.studies.lab.lab_params import VARIANTS, LabMaterial
from pilegroup.studies.lab.lab_plots import write_lab_figure
from pilegroup.studies.lab.lab_tables import INTERFACE_TESTS, csv_name, write_lab_table
from pilegroup.studies.lab.oedometer_programme import oedometer_test
from pilegroup.studies.lab.soil_tests import SoilProtocol, triaxial_test
from pilegroup.studies.results.tables import Table


@dataclass(frozen=True)
class LabOutput:
    """The files one test wrote and its table."""

    test: str
    csv: Path
    png: Path
    table: Table
    source: str


def lab_table(test: str, material: LabMaterial, interface: InterfaceProtocol,
              soil: SoilProtocol, variants: tuple[str, ...] = VARIANTS) -> Table:
    """The table of ``test`` for ``material`` (both Eq. 15 readings unless ``variants``)."""
    if test in INTERFACE_TESTS:
        return run_interface_test(test, material.interface_laws(test), interface, variants)
    law = material.soil_law(test)
    if test == "triaxial":
        return triaxial_test(law, soil)
    return oedometer_test(law, float(material.need("e0", test)), soil)


def run_lab(test: str, material: LabMaterial, out: Path, interface: InterfaceProtocol,
            soil: SoilProtocol, variants: tuple[str, ...] = VARIANTS) -> LabOutput:
    """Run ``test`` and write ``out/<test>.csv`` and ``out/<test>.png``."""
    table = lab_table(test, material, interface, soil, variants)
    csv = write_lab_table(out / csv_name(test), test, table)
    png = write_lab_figure(out / f"{test}.png", test, table, f"{test}, {material.source}")
    return LabOutput(test, csv, png, table, material.source)


__all__ = ["LabOutput", "lab_table", "run_lab"]
