"""What the paper (Li et al. 2019) reports that the run's figures and summary compare with."""

from __future__ import annotations

#: The soft layers of Table 1 of the paper: (1) clay, (2) mud, (3) mucky clay.
SOFT_LAYERS = (1, 2, 3)
#: The paper's "0 days to 89 days" early period (Section 2, text on Figures 6-7; Section 5).
EARLY_DAY = 89.0

#: Cap settlement computed by the paper with ABAQUS, cm, by mesh size at the pile surface (m):
#: Section 5, Table 2 "Settlement of pile foundation calculated by numerical simulation with
#: different mesh sizes". The paper adopts 0.3 m ("the optimal mesh size ... is 0.3m"). The table
#: states no time; the simulation runs 317 days (Section 5). The paper reports no *measured*
#: settlement of the pier (its field data are strains, friction and relative displacement).
PAPER_SETTLEMENT_CM: dict[float, float] = {1.0: 36.5, 0.8: 35.2, 0.6: 34.6, 0.3: 30.3, 0.1: 30.2}
PAPER_MESH_M = 0.3

#: Times (days) of the gauge profile figures: the start and end of the paper's 317 days of
#: monitoring (Section 2), its 89-day early period and two times between; a run's figures use
#: its nearest output times.
PAPER_PROFILE_DAYS = (0.0, 30.0, 89.0, 180.0, 317.0)
#: Gauge sections whose measured histories the paper compares with its simulation (Section 5,
#: Figures 12 and 13: test sections 1, 5, 11 and 17).
PAPER_HISTORY_SECTIONS = (1, 5, 11, 17)
#: The paper's Table 2 (Section 5, "Settlement of pile foundation calculated by numerical
#: simulation with different mesh sizes"), by mesh size at the pile surface (m): element number
#: of the ABAQUS model (the whole pier) and computation time in hours; the settlements are
#: :data:`PAPER_SETTLEMENT_CM`. The paper names no machine.
PAPER_ELEMENTS: dict[float, int] = {1.0: 57108, 0.8: 63553, 0.6: 71141, 0.3: 105522,
                                    0.1: 255221}
PAPER_HOURS: dict[float, float] = {1.0: 0.2, 0.8: 0.9, 0.6: 1.2, 0.3: 6.8, 0.1: 42.6}
