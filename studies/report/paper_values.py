"""The paper's mesh-size study (Li et al. 2019, Section 5, Table 2), for ``pilegroup study mesh``.

A run's figures and report take published values from its scenario's ``[reference]`` table
(:class:`~pilegroup.model.reference.Reference`; ``pier667`` carries the paper's), never from
here.
"""

from __future__ import annotations

#: Cap settlement computed by the paper with ABAQUS, cm, by mesh size at the pile surface (m):
#: Section 5, Table 2 "Settlement of pile foundation calculated by numerical simulation with
#: different mesh sizes". The paper adopts 0.3 m ("the optimal mesh size ... is 0.3m"). The table
#: states no time; the simulation runs 317 days (Section 5). The paper reports no *measured*
#: settlement of the pier (its field data are strains, friction and relative displacement).
PAPER_SETTLEMENT_CM: dict[float, float] = {1.0: 36.5, 0.8: 35.2, 0.6: 34.6, 0.3: 30.3, 0.1: 30.2}

#: The paper's Table 2 (Section 5, "Settlement of pile foundation calculated by numerical
#: simulation with different mesh sizes"), by mesh size at the pile surface (m): element number
#: of the ABAQUS model (the whole pier) and computation time in hours; the settlements are
#: :data:`PAPER_SETTLEMENT_CM`. The paper names no machine.
PAPER_ELEMENTS: dict[float, int] = {1.0: 57108, 0.8: 63553, 0.6: 71141, 0.3: 105522,
                                    0.1: 255221}
PAPER_HOURS: dict[float, float] = {1.0: 0.2, 0.8: 0.9, 0.6: 1.2, 0.3: 6.8, 0.1: 42.6}
