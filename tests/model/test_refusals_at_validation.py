"""Every refusal a run makes for a reason in the scenario, ``scenario validate`` makes too.

:data:`CASES` walks the refusals the run path (after the scenario is loaded) can make for a
reason in the scenario; each is made by ``pilegroup scenario validate`` with exit code 2 and
one line, before any meshing, and a few are checked to give ``pilegroup run`` the same line
without touching the output folder.

:data:`CATALOGUE` lists every raising site of the run path (the modules a run imports below
``model/``: geometry, solver, the laws, ``studies/run``), function by function, site by site
in source order: a case of :data:`CASES` that shows validation makes the refusal, or why the
site is not one a scenario reaches before meshing (``guard``: the pipeline builds the input
from a validated scenario, which a scenario rule already restricts; ``mesher``: only meshing
tells; ``machine``; ``command line``; ``folder``; ``run``: a failure of the run, not of its
input). :func:`test_every_raising_site_of_the_run_path_is_catalogued` reads the sources: a new
refusal on the run path fails it until it is catalogued (and, if a scenario can reach it,
made at validation with a case here).
"""

import ast
import json
from pathlib import Path

import pytest

from pilegroup.model import bundled_text
from pilegroup.studies.cli.commands import EXIT_INPUT, main

ROOT = Path(__file__).resolve().parents[2]

SINGLE = bundled_text("single_pile")
#: single_pile with two piles placed by a layout (x = -2 and 2 m), no cap.
LAYOUT = SINGLE.replace("grid = [1, 1]", "layout = [ { x_m = -2.0, y_m = 0.0 },"
                        " { x_m = 2.0, y_m = 0.0 } ]")


def _many_layers(n: int = 100) -> str:
    """single_pile with ``n`` layers of 0.2 m (tied piles: no interface parameters needed)."""
    head = SINGLE[:SINGLE.index("[[layers]]")].replace('mode = "viscoplastic"', 'mode = "tied"')
    layer = ('[[layers]]\nname = "l{j}"\nthickness_m = {t}\ngamma_kN_per_m3 = 18.0\n'
             'E_MPa = 5.0\nnu = 0.3\nphi_deg = 20.0\nc_kPa = 5.0\nk_m_per_day = 1e-4\n'
             'e0 = 1.0\n')
    return head + "\n".join(layer.format(j=j, t=20.0 / n) for j in range(n))


#: A Soft Soil Creep layer 1 and a Modified Cam Clay layer 2 of single_pile (--set keys).
SSC = {"layers[0].model": "soft_soil_creep", "layers[0].lambda_star": 0.1,
       "layers[0].kappa_star": 0.02, "layers[0].mu_star": 0.004, "layers[0].phi_deg": 25.0}
MCC = {"layers[1].model": "modified_cam_clay", "layers[1].lam": 0.15, "layers[1].kappa": 0.03,
       "layers[1].M": 1.0}

BASES = {"single_pile": SINGLE, "layout": LAYOUT, "pier667": bundled_text("pier667"),
         "many_layers": _many_layers()}

#: (id, base scenario, --set keys, the fragment of the one line). Every case was refused by a
#: run only (most after meshing, some with exit code 1) before validation made it.
CASES = [
    ("symmetry-load", "single_pile",
     {"stages[1].Fx_kN": 100.0, "numerics.symmetry": "quarter"},
     "numerics.symmetry = 'quarter': cuts at x = 0, but the load is not mirror-symmetric"),
    ("symmetry-geometry", "layout", {"piles.layout[1].x_m": 3.0, "numerics.symmetry": "half_x"},
     "numerics.symmetry = 'half_x': cuts at x = 0, but the geometry is not mirror-symmetric"),
    ("too-many-layers", "many_layers", {}, "layers = 100 (-): at most 99 layers"),
    ("piles-touching", "layout", {"piles.layout[0].x_m": -0.4, "piles.layout[1].x_m": 0.4},
     "piles.layout[1] (pile 2) = (0.4, 0.0) (m): overlaps pile 1: centre distance 0.8 m"),
    ("no-cap-margin", "layout", {"piles.layout[1].x_m": 7.0},
     "site = [16.0, 16.0] (m): the cap / pile region [-3.9, 8.9] x [-1.9, 1.9] m must lie"),
    ("pile-cell-edge", "layout", {"piles.layout[0].x_m": 0.0, "piles.layout[1].x_m": 0.9,
                                  "piles.layout[1].y_m": 3.0},
     "piles.layout[0] (pile 1) = [0.0, 0.0] (m): leaves only 0.05 m to its structured cell"),
    ("pile-cell-edge-grid", "pier667", {"piles.spacing_m": [1.1, 2.5]},
     "piles.grid = [-1.1, -2.5] (m): pile 1: leaves only 0.05 m to its structured cell edge"),
    ("plastic-soil-without-strength", "single_pile",
     {"layers[0].c_kPa": 0.0, "layers[0].phi_deg": 0.0},
     "layers[0].c_kPa (layer 1) = 0.0 (kPa): with phi_deg = 0 the layer has no strength"),
    ("interface-delta-from-phi-0", "single_pile",
     {"layers[0].phi_deg": 0.0,
      "layers[0].interface": {"K": 296, "n": 0.29, "R_f": 0.27, "eta_MPa_day": 6.23}},
     "layers[0].interface.delta_deg (layer 1) = None (degree): missing: Eq. 17 gives delta = 0"),
    ("interface-delta-zero", "single_pile", {"layers[1].interface.delta_deg": 0.0},
     "layers[1].interface.delta_deg (layer 2) = 0.0 (degree): must be in (0, 60)"),
    ("gauss-with-q2q1", "single_pile",
     {"interface.quadrature": "gauss", "numerics.element": "Q2Q1"},
     "interface.quadrature = 'gauss': needs numerics.element = 'Q1Q1'"),
    ("installation-pore-pressure", "single_pile",
     {"piles.installation": {"excess_pore_pressure_ratio": 0.95, "radius_ratio": 10.0}},
     "piles.installation.excess_pore_pressure_ratio = 0.95 (-): the installation pore pressure"
     " reaches 1.07 times"),
    ("installation-with-tied-piles", "single_pile",
     {"stages[1]": {"name": "install", "kind": "installation"}, "interface.mode": "tied"},
     "interface.mode = 'tied': an installation stage needs interface.mode 'elastic'"),
    ("interface-base-false", "single_pile", {"interface.base": False},
     "interface.base = False (-): only true (an interface under every pile base)"),
    # the soft-soil models of a layer (docs/model.md, "Soil models per layer")
    ("ssc-kappa-star", "single_pile", {**SSC, "layers[0].kappa_star": 0.2},
     "layers[0].kappa_star (layer 1) = 0.2 (-): must be < lambda_star = 0.1"),
    ("ssc-mu-star-negative", "single_pile", {**SSC, "layers[0].mu_star": -0.001},
     "layers[0].mu_star (layer 1) = -0.001 (-): must be in (0, 0.1]"),
    ("ssc-phi-zero", "single_pile",
     {**SSC, "layers[0].phi_deg": 0.0, "layers[0].interface.delta_deg": 2.0},
     "layers[0].phi_deg (layer 1) = 0.0 (degree): must be > 0 with soil model"),
    ("ssc-no-ellipse", "single_pile", {**SSC, "layers[0].phi_deg": 40.0,
                                       "layers[0].kappa_star": 0.05, "layers[0].nu_ur": 0.45},
     "layers[0].phi_deg (layer 1) = 40.0 (degree): gives K0nc = 1 - sin phi = 0.3572, too small"),
    ("ocr-below-1", "single_pile", {**SSC, "layers[0].OCR": 0.8},
     "layers[0].OCR (layer 1) = 0.8 (-): must be in [1, 100]"),
    ("ocr-and-pop", "single_pile", {**MCC, "layers[1].OCR": 1.5, "layers[1].POP_kPa": 10.0},
     "layers[1].POP_kPa (layer 2) = 10.0 (kPa): give either OCR or POP_kPa, not both"),
    ("mcc-kappa", "single_pile", {**MCC, "layers[1].kappa": 0.2},
     "layers[1].kappa (layer 2) = 0.2 (-): must be < lam = 0.15"),
    ("mcc-without-M", "single_pile", {k: v for k, v in MCC.items() if k != "layers[1].M"},
     "layers[1].M (layer 2) = None (-): missing key; expected a number (soil model"
     " 'modified_cam_clay' uses M, or phi_cs_deg instead)"),
]
CASE_IDS = [c[0] for c in CASES]
#: The cases also run through ``pilegroup run``: the same line, nothing written.
RUN_CASES = ["symmetry-load", "pile-cell-edge", "gauss-with-q2q1", "installation-pore-pressure",
             "plastic-soil-without-strength", "ssc-kappa-star"]


def _toml(value: object) -> str:
    """``value`` as a TOML value (what ``--set KEY=VALUE`` takes)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def _argv(tmp_path: Path, base: str, sets: dict) -> list[str]:
    path = tmp_path / f"{base}.toml"
    if not path.exists():
        path.write_text(BASES[base])
    return [str(path), *[a for k, v in sets.items() for a in ("--set", f"{k}={_toml(v)}")]]


def _refusal(rc: int, err: str) -> str:
    """The one line of an exit-2 refusal."""
    assert rc == EXIT_INPUT, (rc, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pilegroup: invalid input: "), err
    return lines[0]


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
def test_validate_refuses_with_one_line(case, tmp_path, capsys):
    _, base, sets, fragment = case
    rc = main(["scenario", "validate", *_argv(tmp_path, base, sets)])
    line = _refusal(rc, capsys.readouterr().err)
    assert fragment in line, line


@pytest.mark.parametrize("name", RUN_CASES)
def test_run_refuses_with_the_same_line_before_its_folder(name, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    _, base, sets, _ = CASES[CASE_IDS.index(name)]
    argv = _argv(tmp_path, base, sets)
    line = _refusal(main(["scenario", "validate", *argv]), capsys.readouterr().err)
    out = tmp_path / "out"
    assert _refusal(main(["run", *argv, "--out", str(out)]), capsys.readouterr().err) == line
    assert not out.exists() and not (tmp_path / "cache").exists()


def test_a_linear_elastic_soil_needs_no_strength_keys(tmp_path, capsys):
    doc = SINGLE.replace('model = "mohr_coulomb"', 'model = "linear_elastic"').replace(
        'mode = "viscoplastic"', 'mode = "tied"')
    doc = "\n".join(line for line in doc.splitlines()
                    if not line.startswith(("phi_deg", "c_kPa", "interface =")))
    f = tmp_path / "elastic.toml"
    f.write_text(doc)
    assert main(["scenario", "validate", str(f)]) == 0, capsys.readouterr().err
    assert main(["scenario", "validate", str(f), "--set", "soil.model=mohr_coulomb"]) == 2
    assert "layers[0].phi_deg (layer 1) = None: missing key; expected a number (the soil model" \
           " 'mohr_coulomb' uses it)" in capsys.readouterr().err
    elastic = ["--set", "interface.mode=elastic"] + [
        a for j in (0, 1) for a in ("--set", f"layers[{j}].interface={{ K = 296, n = 0.29,"
                                             " R_f = 0.27 }")]
    assert main(["scenario", "validate", str(f), *elastic]) == 2
    assert "layers[0].phi_deg (layer 1) = None: missing key; expected a number (the layer's" \
           " interface law (interface.mode = 'elastic') uses it)" in capsys.readouterr().err


def test_messages_count_layers_stages_and_piles_from_1(tmp_path, capsys):
    for sets, entry in (({"layers[1].nu": 0.7}, "layers[1].nu (layer 2) = 0.7"),
                        ({"stages[2].until_day": -5.0}, "stages[2].until_day (stage 3)"),
                        ({"piles.layout[1].diameter_m": -1.0},
                         "piles.layout[1].diameter_m (pile 2) = -1.0")):
        rc = main(["scenario", "validate", *_argv(tmp_path, "layout", sets)])
        assert entry in _refusal(rc, capsys.readouterr().err)


# ---- the run path's raising sites ----------------------------------------------------------

#: Error classes (and the names a module raises them by) that refuse input.
INPUT_ERRORS = {"ScenarioError", "SolverInputError", "ConstitutiveError", "MachineTooSmall",
                "FolderBusy", "cls", "_refuse"}
#: The folders of the run path below the scenario (``model/`` is the validation itself).
RUN_FOLDERS = ("geometry", "solver", "constitutive", "studies/run")

G, M, R, CL, F = ("guard", "mesher", "run", "command line", "folder")
#: "file::function" -> one disposition per raising site, in source order: a case id of CASES,
#: or why a scenario does not reach it before meshing (the words below).
CATALOGUE: dict[str, tuple[str, ...]] = {
    # guards: the scenario's own rules on the same values are as strict or stricter
    "geometry/adapter.py::_resolve": ("symmetry-load",),
    "geometry/spec.py::BlockSpec.__post_init__": (G,) * 3,
    "geometry/spec.py::LayerSpec.__post_init__": (G,) * 3,
    "geometry/spec.py::PileSpec.__post_init__": (G,) * 5,
    "geometry/spec.py::CapSpec.__post_init__": (G,) * 4,
    "geometry/spec.py::MeshSizing.__post_init__": (G,) * 5,
    "geometry/spec.py::GeometrySpec.__post_init__": (G,),  # levels: the water table's depth
    "geometry/spec.py::GeometrySpec._check_layers": (G, "too-many-layers", G, G, G),
    # no piles, too many, too long, embedment without cap / too deep, outside the cap: the
    # scenario's rules; touching piles and the region without a cap: geometry's own
    "geometry/spec.py::GeometrySpec._check_piles": (G, G, G, G, G, G, "piles-touching",
                                                    "no-cap-margin"),
    "geometry/spec.py::GeometrySpec._check_symmetry": (G, "symmetry-geometry"),
    # two piles in one cell coincide: refused as overlapping first
    "geometry/plan.py::cell_grid": (G, "pile-cell-edge"),
    "geometry/far_field.py::far_field": (M,),  # gmsh finds no convex quadrilateral far field
    "geometry/convert.py::check_mesh": (M,),  # the mesh gmsh made is invalid
    "geometry/convert.py::_share_error": (M,),  # the meshing rank's refusal on every rank
    "studies/run/auto_preset.py::auto_preset": (G,),  # the table's last row matches any size
    "studies/run/checkpoint.py::check_resume": (F,) * 6,  # --resume and the folder's checkpoint
    "studies/run/checkpoint.py::Checkpoints.restore": (F,),
    # a checkpoint whose pile sections are of another kind: the folder, not the scenario
    "studies/run/section_probe.py::PileSections.restore_state": (F,),
    "studies/run/folder_lock.py::folder_lock": (F,),  # --out held by another run
    "studies/run/job.py::run_scenario": (CL,),  # --stop-after with --resume
    "studies/run/memory_check.py::memory_check": ("machine",),  # the memory available
    "studies/run/stiffness.py::scenario_until": (CL, CL),  # --day
    # the soft-soil laws: lam, kappa, e0, M, phi_cs, nu, G (never given), OCR/POP, K0nc (1 -
    # sin phi_cs of M or phi_cs_deg); the stress at rest has p' > 0 (initial_state)
    "constitutive/cam_clay.py::_require_one": ("mcc-without-M",),
    "constitutive/cam_clay.py::ModifiedCamClay.__post_init__": (
        G, "mcc-kappa", G, G, G, G, G, "ocr-below-1", G),
    "constitutive/cam_clay.py::ModifiedCamClay._return": (R,),
    "constitutive/critical_state.py::require_ocr_pop": ("ocr-below-1", G, "ocr-and-pop"),
    "constitutive/critical_state.py::initial_stress": (G, G),
    "constitutive/critical_state.py::ElasticTrial.__init__": (R,),
    "constitutive/critical_state.py::bracketed_newton": (R,),
    # lambda*, kappa*, mu*, phi, c, nu_ur, OCR/POP, K0nc (not given), tau
    "constitutive/soft_soil_creep.py::SoftSoilCreep.__post_init__": (
        G, "ssc-kappa-star", "ssc-mu-star-negative", "ssc-phi-zero", G, G, "ocr-below-1", G, G),
    "constitutive/base.py::as_points": (G,),
    "constitutive/base.py::broadcast_state": (G,),
    # K, n, R_f, c, phi, eta, k_normal, delta, delta from phi = 0, N, r_w, P_a, p_floor,
    # variant, integrator, bearing, fade_stiffness
    "constitutive/interface_law.py::PileSoilInterface.__post_init__": (
        G, G, G, G, G, G, G, "interface-delta-zero", "interface-delta-from-phi-0", G, G, G, G,
        G),
    "constitutive/interface_law.py::PileSoilInterface.initial_state": (G,) * 3,
    "constitutive/interface_law.py::PileSoilInterface.update": (G,),
    "constitutive/interface_law.py::PileSoilInterface._return": (R,),
    "constitutive/soil.py::require_elastic_constants": (G, G),
    "constitutive/soil.py::_Elastic.__post_init__": (G,),
    "constitutive/soil.py::_ElastoPlastic.__post_init__": (G, G, G,
                                                           "plastic-soil-without-strength"),
    "constitutive/soil.py::MohrCoulomb._return": (R,),
    "solver/constraints.py::Constraints.__init__": (G, G),
    "solver/constraints.py::RigidPlateControl.__init__": (G,),
    "solver/forms.py::_check_cells_off_water_table": (G,),  # the mesh has a level there
    "solver/geostatic.py::SoilColumn.check_installation": ("installation-pore-pressure",),
    "solver/inputs.py::SoilMaterial.__post_init__": (G,) * 9,
    "solver/inputs.py::ElasticSolid.__post_init__": (G,),
    "solver/inputs.py::InstallationExcess.__post_init__": (G,) * 3,
    # quadrature, shaft factor (the mesher's polygon: always in range), laws
    "solver/inputs.py::InterfaceCoupling.__post_init__": (G, G, G),
    "solver/inputs.py::Discretisation.__post_init__": (G, G),
    "solver/inputs.py::NewtonOptions.__post_init__": (G,),
    "solver/inputs.py::SolverOptions.__post_init__": (G,),
    "solver/inputs.py::StepControl.__post_init__": (G,) * 5,
    "solver/inputs.py::PressureBC.__post_init__": (G,),
    "solver/inputs.py::FaceAction.__post_init__": (G, G),
    "solver/inputs.py::SolverStage.__post_init__": (G,) * 5,
    "solver/layout.py::BlockLayout.__init__": (G,),
    "solver/layout.py::BlockLayout._check_coverage": (G, G),
    "solver/layout.py::BlockLayout.splits": (G,),
    "solver/layout.py::BlockLayout.interface_soil_nodes": (G,),
    "solver/presets.py::get_preset": (G,),
    "solver/linsolve.py::create_ksp": (G,),
    "solver/mumps.py::OutOfCoreFolder.__init__": ("machine",),  # a folder for the factors
    "solver/problem.py::BiotProblem.__init__": ("installation-with-tied-piles",),
    "solver/problem.py::BiotProblem._define_interface": ("gauss-with-q2q1",),
    "solver/problem.py::BiotProblem.interface_force": (G,),
    "solver/problem.py::BiotProblem.set_ground": (G,),
    "solver/problem.py::BiotProblem.install_structure": (G,),
    "solver/state.py::restore_problem_state": (F,),  # --resume: the checkpoint's partition
    "solver/state.py::check_same_partition": (F,),
}
WORDS = {G, M, R, CL, F, "machine"}


def _module_files() -> dict[str, Path]:
    """Every module of the package: dotted name -> file (the layout of test_structure)."""
    folders = {"model": "pilegroup.model", "geometry": "pilegroup.geometry",
               "constitutive": "pilegroup.constitutive", "solver": "pilegroup.solver",
               "studies": "pilegroup.studies", "src/pilegroup": "pilegroup"}
    out = {}
    for folder, pkg in folders.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = [p for p in path.relative_to(ROOT / folder).with_suffix("").parts
                     if p != "__init__"]
            out[".".join([pkg, *parts])] = path
    return out


def _run_path() -> list[Path]:
    """The files a run imports (from ``studies/run/job.py``) in :data:`RUN_FOLDERS`."""
    files = _module_files()
    seen, todo = set(), ["pilegroup.studies.run.job"]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        for node in ast.walk(ast.parse(files[name].read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                todo += [m for m in (node.module, *(f"{node.module}.{a.name}"
                                                    for a in node.names)) if m in files]
            elif isinstance(node, ast.Import):
                todo += [a.name for a in node.names if a.name in files]
    paths = [files[m].relative_to(ROOT) for m in seen]
    return sorted(p for p in paths if p.as_posix().startswith(RUN_FOLDERS))


def _raising_sites(path: Path) -> dict[str, int]:
    """``"file::function" -> number of sites``: input errors raised, ``require_*`` checks."""
    out: dict[str, int] = {}

    def visit(node: ast.AST, qual: str) -> None:
        for child in ast.iter_child_nodes(node):
            q = qual
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                q = f"{qual}.{child.name}" if qual else child.name
            call = child.exc if isinstance(child, ast.Raise) else child
            name = ""
            if isinstance(call, ast.Call):
                f = call.func
                name = f.id if isinstance(f, ast.Name) else getattr(f, "attr", "")
            raised = isinstance(child, ast.Raise) and name in INPUT_ERRORS
            checked = (isinstance(child, ast.Call)
                       and (name.startswith("require_") or name == "check_bound"))
            if raised or checked:
                key = f"{path.as_posix()}::{qual}"
                out[key] = out.get(key, 0) + 1
            visit(child, q)

    visit(ast.parse((ROOT / path).read_text()), "")
    return out


def test_every_raising_site_of_the_run_path_is_catalogued():
    found: dict[str, int] = {}
    for path in _run_path():
        found.update(_raising_sites(path))
    wrong = {k: (n, len(CATALOGUE.get(k, ()))) for k, n in found.items()
             if n != len(CATALOGUE.get(k, ()))}
    gone = sorted(set(CATALOGUE) - set(found))
    assert not wrong and not gone, (
        f"raising sites (found, catalogued) that differ: {wrong}; catalogued but gone: {gone}."
        " A refusal a scenario can reach must be made when the scenario is built (model/) or"
        " by geometry.adapter.resolve_geometry, with a case in CASES; add the site to"
        " CATALOGUE with that case, or with why a scenario does not reach it before meshing")


def test_catalogue_names_cases_and_reasons_only():
    for key, sites in CATALOGUE.items():
        for what in sites:
            assert what in WORDS or what in CASE_IDS, (key, what)
    assert {w for sites in CATALOGUE.values() for w in sites} >= set(RUN_CASES)
