"""The scenario's cap actions as solver loads: unit face actions with amplitudes per stage.

The vertical load is the load factor's pressure on the loaded face (``pipeline.build_problem``);
the other components a scenario uses (horizontal forces, moments, docs/model.md, "Cap
actions") are :class:`~pilegroup.solver.FaceAction` s on the same face, each with an action
amplitude of its own after the ground actions (surcharges, then the water table). A load
stage sets the amplitudes to its components about the face centre; every other stage holds
them.
"""

from __future__ import annotations

from pilegroup.geometry import groups
from pilegroup.geometry.adapter import ResolvedGeometry
from pilegroup.geometry.meshdata import MeshData
from pilegroup.model import Scenario
from pilegroup.model.actions import LATERAL
from pilegroup.solver import FaceAction
from pilegroup.solver.probes import face_geometry


def loaded_facets(sc: Scenario, md: MeshData) -> list[str]:
    """Facet groups that carry the cap actions: the cap top, or the pile heads without a cap."""
    return [groups.CAP_TOP] if sc.cap is not None else groups.heads(md.facet_names)


def used_components(sc: Scenario) -> tuple[int, ...]:
    """The components with a face action of their own.

    The lateral components some load stage sets non-zero (about the face centre); all six
    when the run ends with the cap stiffness matrix (``outputs.cap_stiffness``), which loads
    the face in every component (the vertical one then twice: by the load factor's pressure
    and by its probe's face action, which stays 0 during the run).
    """
    if sc.outputs.cap_stiffness:
        return tuple(range(6))
    acts = [a for _, a in sc.cap_actions()]
    return tuple(k for k in LATERAL if any(abs(a[k]) > 0.0 for a in acts))


def first_slot(sc: Scenario) -> int:
    """Index of the first cap action among the action amplitudes (after the ground's)."""
    n_surcharge = sum(1 for st in sc.stages if st.kind == "surcharge")
    return n_surcharge + any(st.kind == "groundwater" for st in sc.stages)


def face_properties(md: MeshData, names: list[str], centre: tuple[float, float, float],
                    fraction: float) -> tuple[float, float, float]:
    """(area m^2, I_xx, I_yy m^4 about ``centre``) of the whole face the groups ``names`` hold.

    A symmetry-reduced mesh holds ``fraction`` of a face symmetric about its cut planes
    (through the centre), so the whole face's values are the meshed ones over ``fraction``.
    """
    area, ixx, iyy = face_geometry(md, names, centre)
    return area / fraction, ixx / fraction, iyy / fraction


def face_actions(sc: Scenario, geo: ResolvedGeometry, md: MeshData) -> list[FaceAction]:
    """One unit face action per lateral component the scenario uses, on the loaded face."""
    comps = used_components(sc)
    if not comps:
        return []
    names = loaded_facets(sc, md)
    centre = sc.load_centre()
    area, ixx, iyy = face_properties(md, names, centre, geo.kept_fraction)
    slot = first_slot(sc)
    return [FaceAction(name, k, slot + j, centre, area, (ixx, iyy))
            for j, k in enumerate(comps) for name in names]


def stage_amplitudes(sc: Scenario) -> dict[int, tuple[float, ...]]:
    """Stage index -> the cap actions' amplitudes (kN, kN m) at the end of that load stage.

    The vertical component's face action (only with ``outputs.cap_stiffness``) stays 0: the
    load factor carries the vertical load.
    """
    comps = used_components(sc)
    return {i: tuple(0.0 if k == 2 else float(a[k]) for k in comps)
            for i, a in sc.cap_actions()}


__all__ = ["face_actions", "face_properties", "first_slot", "loaded_facets",
           "stage_amplitudes", "used_components"]
