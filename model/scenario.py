"""The scenario: a frozen, typed, validated description of one pile-group analysis.

:class:`Scenario` gathers the parts defined in :mod:`pilegroup.model.site` (soil block, layers,
cap, structure), :mod:`pilegroup.model.piles`, :mod:`pilegroup.model.stages` and
:mod:`pilegroup.model.analysis` (options, time, numerics, outputs), checks the rules that tie
the parts together, and derives layer depths and stage times. Errors are
:class:`~pilegroup.errors.ScenarioError` naming the key, value, unit and what is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.model.actions import LATERAL, Actions, held_actions, transfer
from pilegroup.model.analysis import InterfaceOptions, Numerics, Outputs, Soil, Time
from pilegroup.model.insitu import check_groundwater, vertical_effective_stress
from pilegroup.model.law_rules import check_all as check_law_inputs
from pilegroup.model.mesh_defaults import describe, locking_warning, resolve_numerics
from pilegroup.model.mesh_estimate import MAX_CELLS, estimated_cells
from pilegroup.model.mirror import kept_fraction
from pilegroup.model.piles import Piles
from pilegroup.model.reference import Reference, check_reference
from pilegroup.model.site import Cap, Layer, Site, Structure
from pilegroup.model.soil_models import layer_model
from pilegroup.model.stages import ACTION_KEYS, Stage


@dataclass(frozen=True)
class Scenario:
    """A whole analysis: site, layers, piles, cap, materials, interface, stages, time, numerics."""

    name: str
    """The scenario's name: the default output folder is ``out/<name>``."""
    site: Site
    layers: tuple[Layer, ...]
    piles: Piles
    structure: Structure
    stages: tuple[Stage, ...]
    time: Time
    cap: Cap | None = None
    soil: Soil = field(default_factory=Soil)
    interface: InterfaceOptions = field(default_factory=InterfaceOptions)
    numerics: Numerics = field(default_factory=Numerics)
    outputs: Outputs = field(default_factory=Outputs)
    actions: Actions = field(default_factory=Actions)
    reference: Reference | None = None
    description: str = ""
    """What the scenario is, in words."""

    def __post_init__(self) -> None:
        self._resolve_numerics()
        self._check_layer_stack()
        self._check_plan()
        self._check_cap()
        self._check_stages()
        self._check_installation()
        check_groundwater(self.site, self.layers, self.stages)
        self._check_excess_pore_pressure()
        self._check_interfaces()
        check_law_inputs(self)
        self._check_gauges()
        check_reference(self.reference, len(self.layers), len(self.outputs.gauge_depths_m))
        self._check_numerics()
        self._check_actions()

    def _resolve_numerics(self) -> None:
        """The element pair and every mesh size the scenario leaves out, chosen from it.

        :func:`pilegroup.model.mesh_defaults.resolve_numerics`.
        """
        object.__setattr__(self, "numerics", resolve_numerics(self, self.locking_reason(),
                                                             kept_fraction(self)))

    def locking_reason(self) -> str | None:
        """Why trilinear hexahedra (Q1Q1) would lock in this scenario, or None.

        They lock in bending (horizontal forces or moments on the foundation: ``verify
        lateral-single-pile``, 18 % too stiff) and under isochoric plastic flow (a capacity
        stage in a Mohr–Coulomb or Drucker–Prager soil: the load–settlement curve never
        flattens, docs/model.md, "Capacity").
        """
        if self.has_lateral_actions():
            return "horizontal actions bend the piles"
        if self.capacity_stage is not None and any(
                layer_model(lay, self.soil) != "linear_elastic" for lay in self.layers):
            return "a capacity stage drives the plastic soil to failure"
        return None

    def discretisation(self) -> dict[str, object]:
        """The element pair and mesh sizes the run uses, with where each came from."""
        m = self.numerics.mesh
        return {"element": self.numerics.element, "element_reason": self.numerics.element_reason,
                "mesh": m.given(), "automatic": list(m.automatic)}

    def discretisation_line(self) -> str:
        """The element pair and mesh sizes in one line (automatic sizes marked ``*``)."""
        return describe(self.numerics)

    def discretisation_warning(self) -> str | None:
        """One line when the element pair is known to be inaccurate for the scenario."""
        return locking_warning(self.numerics, self.locking_reason())

    # ---- rules across the parts, in the order the messages report them ----
    def _check_layer_stack(self) -> None:
        """The layers reach below the pile toes and fill the block (or the last one does).

        The deepest toe (the longest pile) decides: it ends above the block bottom with room
        for one element below it, and the layer stack reaches it.
        """
        if not self.layers:
            raise ScenarioError("layers", [], "must list at least one layer")
        for i, layer in enumerate(self.layers[:-1]):
            if layer.thickness_m is None:
                raise ScenarioError(f"layers[{i}].thickness_m", None,
                                    "missing: only the last layer may omit its thickness", "m")
        depth = self.site.depth_m
        lengths = self.piles.lengths
        toe = max(lengths)
        key = self.piles.key_of(lengths.index(toe) + 1, "length_in_soil_m")
        if toe >= depth:
            raise ScenarioError(key, toe,
                                f"must be < site.depth_m = {depth:g} (pile longer than the block)",
                                "m")
        room = self.numerics.mesh.dz_toe_m
        if depth - toe < room:
            raise ScenarioError(key, toe,
                                f"must leave room for one element below the toes: site.depth_m"
                                f" - length >= numerics.mesh.dz_toe_m = {room:g}", "m")
        given = sum(layer.thickness_m or 0.0 for layer in self.layers)
        if self.layers[-1].thickness_m is None:
            if given >= depth:
                raise ScenarioError(f"layers[{len(self.layers) - 1}].thickness_m", None,
                                    f"the layers above already reach {given:g} m >= site.depth_m"
                                    f" = {depth:g} m; nothing is left for the last layer", "m")
            return
        if given < toe:
            raise ScenarioError("layers", f"total thickness {given:g}",
                                f"the layer stack must reach the pile toe at {toe:g} m depth"
                                + (" (the longest pile's)" if min(lengths) < toe else "")
                                + " (or omit the last layer's thickness to extend it to the"
                                " bottom)", "m")
        if abs(given - depth) > 1e-9 * depth:
            raise ScenarioError("layers", f"total thickness {given:g}",
                                f"must equal site.depth_m = {depth:g} (or omit the last"
                                " layer's thickness)", "m")

    def _check_plan(self) -> None:
        """Every pile lies inside the soil block and, when there is one, inside the cap.

        A pile also leaves 0.2 x its radius to the cap edge: the structured mesh around it
        (``pilegroup.geometry.plan.cell_grid``) needs that room.
        """
        half_x, half_y = self.site.size_x_m / 2, self.site.size_y_m / 2
        for n, ((x, y), d) in enumerate(zip(self.piles.xy, self.piles.diameters, strict=True),
                                        start=1):
            r = d / 2
            key = self.piles.position_key(n)
            pile = "the pile" if key != "piles.grid" else f"pile {n}"
            if abs(x) + r > half_x or abs(y) + r > half_y:
                raise ScenarioError(key, [x, y], f"{pile} lies outside the soil block", "m")
            if self.cap is None:
                continue
            clear = min(self.cap.size_x_m / 2 - abs(x), self.cap.size_y_m / 2 - abs(y)) - r
            if clear < -1e-12:
                raise ScenarioError(key, [x, y], f"{pile} (diameter {d:g} m) lies outside the"
                                    f" cap ({self.cap.size_x_m:g} x {self.cap.size_y_m:g} m)", "m")
            if clear < 0.2 * r:
                raise ScenarioError(key, [x, y],
                                    f"{pile} leaves only {clear:.3g} m to the cap edge: need >="
                                    f" 0.2 x the radius = {0.2 * r:g} m for the structured mesh"
                                    " around the pile", "m")

    def _check_cap(self) -> None:
        """The cap fits the block in plan and holds the embedded pile heads."""
        if self.cap is None:
            if self.piles.embedment_m > 0.0:
                raise ScenarioError("piles.embedment_m", self.piles.embedment_m,
                                    "must be 0 when there is no cap", "m")
            return
        for key in ("size_x_m", "size_y_m"):
            if getattr(self.cap, key) >= getattr(self.site, key):
                raise ScenarioError(f"cap.{key}", getattr(self.cap, key),
                                    f"must be < site.{key} = {getattr(self.site, key):g}: the cap"
                                    " must lie strictly inside the soil block in plan", "m")
        if self.piles.embedment_m >= self.cap.thickness_m:
            raise ScenarioError("piles.embedment_m", self.piles.embedment_m,
                                f"must be < cap.thickness_m = {self.cap.thickness_m:g}", "m")
        tied = self.interface.mode == "tied"
        if self.cap.in_contact_with_soil is not None and self.cap.in_contact_with_soil != tied:
            raise ScenarioError(
                "cap.in_contact_with_soil", self.cap.in_contact_with_soil,
                "must follow the interface model (or be left out): with interface.mode = "
                "'tied' the cap bottom is bonded to the ground (true); with 'elastic' or "
                "'viscoplastic' the cap is free of the soil (false); a cap-soil interface is "
                "not modelled", "-")

    def _check_installation(self) -> None:
        """At most one installation stage; every cap load after it; an interface to engage."""
        kinds = [st.kind for st in self.stages]
        if "installation" not in kinds:
            return
        i = kinds.index("installation")
        if "installation" in kinds[i + 1:]:
            j = kinds.index("installation", i + 1)
            raise ScenarioError(f"stages[{j}].kind", "installation",
                                f"the piles are installed once (stage {i + 1}, stages[{i}],"
                                " already installs them)")
        if "load" in kinds[:i]:
            j = kinds.index("load")
            raise ScenarioError(f"stages[{j}].kind", "load",
                                f"a cap load before the piles exist: put it after the"
                                f" installation stage, stage {i + 1} (stages[{i}])")
        if self.interface.mode == "tied":
            raise ScenarioError("interface.mode", "tied",
                                "an installation stage needs interface.mode 'elastic' or"
                                " 'viscoplastic' (before it the soil moves past the piles'"
                                " place; tied piles move with it from the start)")

    def _check_stages(self) -> None:
        """One geostatic stage first; the other stages end by ``time.end_day``; areas fit."""
        if not self.stages:
            raise ScenarioError("stages", [], "must list at least one stage")
        if self.stages[0].kind != "geostatic":
            raise ScenarioError("stages[0].kind", self.stages[0].kind,
                                "the first stage must be 'geostatic'")
        t = self.time.start_day
        for i, st in enumerate(self.stages):
            if i > 0 and st.kind == "geostatic":
                raise ScenarioError(f"stages[{i}].kind", st.kind,
                                    "only the first stage may be 'geostatic'")
            if st.duration_day is not None:
                t += st.duration_day
                if t > self.time.end_day:
                    raise ScenarioError("time.end_day", self.time.end_day,
                                        f"must be >= the end of {st.kind} stage {st.name!r} at"
                                        f" {t:g} day", "day")
            elif st.kind == "consolidation":
                until = self.time.end_day if st.until_day is None else st.until_day
                if until <= t or until > self.time.end_day:
                    raise ScenarioError(f"stages[{i}].until_day", until,
                                        f"must be in ({t:g}, time.end_day = "
                                        f"{self.time.end_day:g}]", "day")
                t = until
            if st.kind == "surcharge":
                self._check_surcharge(i, st)
        self._check_capacity()

    def _check_capacity(self) -> None:
        """A capacity stage is the last stage and raises the load beyond the cap load so far."""
        kinds = [st.kind for st in self.stages]
        if "capacity" not in kinds:
            return
        i = kinds.index("capacity")
        if i != len(kinds) - 1:
            raise ScenarioError(f"stages[{i}].kind", "capacity",
                                f"must be the last stage (stage {i + 2} follows it): the"
                                " foundation has failed at its end")
        st = self.stages[i]
        before = [s.vertical_kN for s in self.stages[:i] if s.kind == "load"]
        if before and st.max_load_kN <= before[-1]:  # type: ignore[operator]
            raise ScenarioError(f"stages[{i}].max_load_kN", st.max_load_kN,
                                f"must be > the cap load before it ({before[-1]:g} kN)", "kN")

    def _check_surcharge(self, i: int, st: Stage) -> None:
        """The loaded rectangle lies on the ground surface."""
        if st.area_m is None:
            return
        hx, hy = self.site.size_x_m / 2, self.site.size_y_m / 2
        x0, x1, y0, y1 = st.area_m
        if x0 < -hx - 1e-9 or x1 > hx + 1e-9 or y0 < -hy - 1e-9 or y1 > hy + 1e-9:
            raise ScenarioError(f"stages[{i}].area_m", list(st.area_m),
                                f"must lie on the ground surface: x in [{-hx:g}, {hx:g}],"
                                f" y in [{-hy:g}, {hy:g}]", "m")

    def _check_excess_pore_pressure(self) -> None:
        """A layer's initial excess pore pressure leaves its effective stress compressive.

        It acts below the water table only: the layer's top, or the water table in it.
        """
        for i, layer in enumerate(self.layers):
            sv = self.vertical_effective_stress(max(self.layer_top(i),
                                                    self.site.water_table_depth_m))
            if layer.excess_pore_pressure_kPa > sv + 1e-9:
                raise ScenarioError(f"layers[{i}].excess_pore_pressure_kPa",
                                    layer.excess_pore_pressure_kPa,
                                    f"must be <= the vertical effective stress at the layer's"
                                    f" top ({sv:.4g} kPa; at the water table if it lies in the"
                                    " layer), or the soil would start with tensile effective"
                                    " stress; use excess_pore_pressure_ratio", "kPa")

    def _check_interfaces(self) -> None:
        """Every layer the piles cross has interface parameters, unless the piles are tied.

        The ``fieldsplit_pier`` and ``fieldsplit_kept`` solver presets split the structure from
        the soil and so need piles joined to the soil by the interface.
        """
        if self.interface.mode == "tied":
            preset = self.numerics.solver.preset
            if preset in ("fieldsplit_pier", "fieldsplit_kept"):
                raise ScenarioError("numerics.solver.preset", preset,
                                    "needs interface.mode 'elastic' or 'viscoplastic' (the piles"
                                    " as a body of their own); with tied piles: 'auto', 'direct',"
                                    " 'direct_reuse' or 'fieldsplit_gamg'")
            return
        toe = max(self.piles.lengths)
        for i, layer in enumerate(self.layers):
            if layer.interface is None and self.layer_top(i) < toe:
                raise ScenarioError(f"layers[{i}].interface", None,
                                    f"missing: the piles cross layer {layer.name!r} and"
                                    f" interface.mode = {self.interface.mode!r}")
        self._check_base_bearing()

    def _check_base_bearing(self) -> None:
        """A base bearing limit exceeds the in-situ vertical effective stress at the toes.

        The limit is the base's largest (gross) effective compression; the in-situ stress
        (hydrostatic pore pressure, the layers' initial excess pore pressure aside) is what the
        base carries before any load. A smaller limit would fail the base under the pile's own
        weight.
        """
        for n, length in enumerate(self.piles.lengths, start=1):
            j = self.layer_at(length)
            sv = self.vertical_effective_stress(length)
            ip = self.layers[j].interface
            if ip is not None and ip.base_bearing_kPa is not None \
                    and ip.base_bearing_kPa <= sv:
                raise ScenarioError(f"layers[{j}].interface.base_bearing_kPa",
                                    ip.base_bearing_kPa,
                                    f"must exceed the in-situ vertical effective stress at the"
                                    f" toe of pile {n} ({sv:.4g} kPa at {length:g} m): the limit"
                                    " is the gross bearing pressure, e.g. N_c c_u + sigma'_v0",
                                    "kPa")

    def _check_gauges(self) -> None:
        """Gauge sections lie on the piles: on every pile, so above the shortest one's toe."""
        toe = min(self.piles.lengths)
        for i, z in enumerate(self.outputs.gauge_depths_m):
            if z > toe:
                raise ScenarioError(f"outputs.gauge_depths_m[{i}]", z,
                                    f"must be <= the (shortest) pile length in soil {toe:g}:"
                                    " every pile is gauged", "m")

    def _check_numerics(self) -> None:
        """Mesh size against the piles, smallest step against the end, cell-count estimate.

        The mesh size resolves the thinnest pile: at most 5 x the smallest diameter.
        """
        m, d = self.numerics.mesh, min(self.piles.diameters)
        if m.size_m > 5.0 * d:
            key = self.piles.key_of(self.piles.diameters.index(d) + 1, "diameter_m")
            raise ScenarioError("numerics.mesh.size_m", m.size_m,
                                f"must be <= 5 x {key} = {5.0 * d:g} (elements much"
                                " larger than the pile do not resolve it)", "m")
        dt_min = self.numerics.time.dt_min_day
        if dt_min > self.time.end_day:
            raise ScenarioError("numerics.time.dt_min_day", dt_min,
                                f"must be <= time.end_day = {self.time.end_day:g}", "day")
        cells = estimated_cells(self)
        if cells > MAX_CELLS:
            raise ScenarioError("numerics.mesh.size_m", m.size_m,
                                f"the mesh would have about {cells:.3g} cells (estimate), more"
                                f" than {MAX_CELLS:.3g}: coarsen numerics.mesh (size_m,"
                                " far_field_size_m, dz_*) or shrink the site", "m")

    # ---- derived quantities (internal units) ----
    def layer_top(self, i: int) -> float:
        """Depth (m, positive down) of the top of layer ``i``."""
        return sum(layer.thickness_m or 0.0 for layer in self.layers[:i])

    def layer_bottom(self, i: int) -> float:
        """Depth (m, positive down) of the bottom of layer ``i`` (the block bottom for the last)."""
        if i == len(self.layers) - 1:
            return self.site.depth_m
        return self.layer_top(i) + self.layers[i].thickness_m  # type: ignore[operator]

    def layer_at(self, depth: float) -> int:
        """Index of the layer holding ``depth`` (m, positive down; a boundary: the upper one)."""
        return next((j for j in range(len(self.layers)) if self.layer_bottom(j) >= depth),
                    len(self.layers) - 1)

    def vertical_effective_stress(self, depth: float) -> float:
        """In-situ vertical effective stress (kPa, compression positive) at ``depth`` (m).

        Hydrostatic pore pressure below the water table, the layers' weight above it
        (:mod:`pilegroup.model.insitu`); the layers' initial excess pore pressure is not taken
        off.
        """
        return vertical_effective_stress(self.site, self.layers, depth)

    def layer_depths(self) -> tuple[float, ...]:
        """Depths (m, positive down) of all layer boundaries, from 0 to the block depth."""
        return tuple([0.0] + [self.layer_bottom(i) for i in range(len(self.layers))])

    def stage_times(self) -> tuple[tuple[Stage, float, float], ...]:
        """Each stage with its start and end time (day).

        The geostatic stage and an installation stage are instants (start = end); the first
        starts at ``time.start_day``.
        """
        t = self.time.start_day
        out = []
        for st in self.stages:
            if st.kind in ("geostatic", "installation"):
                out.append((st, t, t))
            elif st.duration_day is not None:
                out.append((st, t, t + st.duration_day))
                t += st.duration_day
            else:
                end = self.time.end_day if st.until_day is None else st.until_day
                out.append((st, t, end))
                t = end
        return tuple(out)

    @property
    def installation_stage(self) -> Stage | None:
        """The stage that installs the piles after the start, or None (wished in place)."""
        return next((st for st in self.stages if st.kind == "installation"), None)

    def total_cap_load(self) -> float:
        """The reference cap load (kN): load factor 1 stands for it.

        A capacity stage's ``max_load_kN`` (the last stage's end); else the largest vertical
        load of the load stages, so that a stage that takes load off (to 0 too) is a load
        factor below 1 of the load it takes off.
        """
        if self.stages and self.stages[-1].kind == "capacity":
            return float(self.stages[-1].max_load_kN)  # type: ignore[arg-type]
        loads = [st.vertical_kN for st in self.stages if st.kind == "load"]
        return float(max(loads)) if loads else 0.0  # type: ignore[type-var]

    def load_centre(self) -> tuple[float, float, float]:
        """Centroid of the loaded face (m): the cap's top face, or the pile heads' centroid."""
        if self.cap is not None:
            return (0.0, 0.0, self.cap.thickness_m)
        x, y = np.mean(np.array(self.piles.xy, dtype=float), axis=0)
        return (float(x), float(y), 0.0)

    def action_point(self) -> tuple[float, float, float]:
        """The point the stages' moments are given about (m): ``actions.point_m`` or the centre."""
        p = self.actions.point_m
        return self.load_centre() if p is None else (float(p[0]), float(p[1]), float(p[2]))

    def cap_actions(self) -> list[tuple[int, np.ndarray]]:
        """(stage index, the six actions about :meth:`load_centre` at its end) per load stage.

        Actions in kN and kN m, z up (``Fz = -cap_load_kN``); components a stage omits are
        held from the stage before (pilegroup.model.actions).
        """
        idx = [i for i, st in enumerate(self.stages) if st.kind == "load"]
        given = [self.stages[i].given_actions() for i in idx]
        P, C = self.action_point(), self.load_centre()
        return [(i, transfer(a, P, C)) for i, a in zip(idx, held_actions(given), strict=True)]

    def has_lateral_actions(self) -> bool:
        """Whether any load stage puts a horizontal force or a moment on the loaded face."""
        return any(np.any(a[list(LATERAL)] != 0.0) for _, a in self.cap_actions())

    def _check_actions(self) -> None:
        """Horizontal forces and moments need one loaded face: a cap, or a single pile.

        A capacity stage raises the vertical load alone, which then acts at the face centre:
        the action point must lie above it.
        """
        if self.cap is None and self.piles.count > 1:
            for i, a in self.cap_actions():
                k = next((k for k in LATERAL if a[k] != 0.0), None)
                if k is not None:
                    raise ScenarioError(
                        f"stages[{i}].{ACTION_KEYS[k]}", float(a[k]),
                        "horizontal forces and moments need a cap to share them between the "
                        f"{self.piles.count} piles (or a single pile); allowed without a cap:"
                        " a vertical load only (with the action point above the group centre)")
        P, C = self.action_point(), self.load_centre()
        if self.capacity_stage is not None and max(abs(P[0] - C[0]), abs(P[1] - C[1])) > 1e-9:
            raise ScenarioError("actions.point_m", list(P), "a capacity stage raises the vertical"
                                f" load at the loaded face's centre ({C[0]:g}, {C[1]:g}): the "
                                "action point must lie above it in plan", "m")

    @property
    def capacity_stage(self) -> Stage | None:
        """The stage that raises the load until the foundation fails, or None."""
        return next((st for st in self.stages if st.kind == "capacity"), None)
