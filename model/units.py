"""Units and physical constants. Inside the code: kN, m, day (stresses in kPa).

Scenario keys carry their unit in the name (``E_MPa``, ``k_m_per_day``, ``eta_MPa_day``); this
module holds the one set of conversion factors used by ``model`` to turn them into internal units.
"""

KPA_PER_MPA = 1000.0
KPA_PER_GPA = 1.0e6
SECONDS_PER_DAY = 86400.0
#: Unit weight of water for Darcy flow and hydrostatics (kN/m^3). (The paper's r_w = 10 kN/m^3
#: of the Clough-Duncan hyperbola is a parameter of the interface law, not this constant.)
GAMMA_WATER = 9.81
#: Bulk modulus of pore water (kPa).
K_WATER = 2.2e6
#: Standard gravity (m/s^2) to turn densities (kg/m^3) into unit weights (kN/m^3).
G = 9.81


def unit_weight_from_density(rho_kg_per_m3: float) -> float:
    """Unit weight in kN/m^3 of a material of density ``rho_kg_per_m3``."""
    return rho_kg_per_m3 * G / 1000.0
