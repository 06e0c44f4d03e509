"""Nonsense must not validate, and every accepted scenario meshes or exits 2.

Mutations of the bundled scenarios (numbers scaled by 1e-300..1e300, sign flips, zero, NaN and
infinity as numbers and as strings, wrong types, missing and extra keys, broken TOML text)
either load or raise :class:`ScenarioError`; through the CLI they exit 0 or 2 with one stderr
line and no traceback; a few that validate are meshed (exit 0 or 2).
"""

import json
import math
import random
import re
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pilegroup.model import (
    BUNDLED,
    Scenario,
    ScenarioError,
    bundled_text,
    load_scenario,
    scenario_from_dict,
)
from pilegroup.model.bounds import BOUNDS
from pilegroup.model.mesh_estimate import estimated_cells
from pilegroup.studies.cli.commands import EXIT_INPUT, main

DOCS = Path(__file__).resolve().parents[2] / "docs" / "model.md"
#: Values that replace a leaf: non-finite numbers, their strings, wrong types.
ODD_VALUES = [0, 0.0, -1.0, math.nan, math.inf, -math.inf, "nan", "inf", "1.0", "", [1.0, 2.0],
              [], {"a": 1}, True, 10**20]


def _leaves(node, path=()):
    """Every (path, value) of the document; tables and lists are leaves too."""
    if path:
        yield path, node
    if isinstance(node, dict):
        items = list(node.items())
    else:
        items = list(enumerate(node)) if isinstance(node, list) else []
    for k, v in items:
        yield from _leaves(v, (*path, k))


def _mutate(doc, path, kind, arg):
    """Apply one mutation to the document ``doc`` (in place) at ``path``."""
    *head, last = path
    parent = doc
    for k in head:
        parent = parent[k]
    value = parent[last]
    if kind == "scale" and isinstance(value, int | float) and not isinstance(value, bool):
        parent[last] = value * 10.0 ** arg
    elif kind == "flip" and isinstance(value, int | float) and not isinstance(value, bool):
        parent[last] = -value
    elif kind == "odd":
        parent[last] = ODD_VALUES[arg % len(ODD_VALUES)]
    elif kind == "delete":
        del parent[last]
    elif kind == "extra" and isinstance(value, dict):
        value["no_such_key"] = 1.0


def _mutated(base, rng):
    """A copy of bundled scenario ``base`` with 1 to 3 random mutations."""
    doc = tomllib.loads(bundled_text(base))
    for _ in range(rng.randint(1, 3)):
        leaves = list(_leaves(doc))
        path, _ = leaves[rng.randrange(len(leaves))]
        kind = rng.choice(["scale", "scale", "flip", "odd", "delete", "extra"])
        _mutate(doc, path, kind, rng.randint(-300, 300))
    return doc


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(base=st.sampled_from(BUNDLED), seed=st.integers(0, 2**32 - 1))
def test_mutated_scenario_loads_or_raises_scenario_error(base, seed):
    doc = _mutated(base, random.Random(seed))
    try:
        sc = scenario_from_dict(doc)
    except ScenarioError as exc:
        assert exc.key and exc.allowed
    else:
        assert isinstance(sc, Scenario)


_LINE = re.compile(r"^(\s*[A-Za-z_][A-Za-z0-9_]*\s*=\s*)(.+)$")
#: Replacement value texts (TOML) for a line of the file.
TEXT_VALUES = ["0", "-1", "nan", "inf", "-inf", '"nan"', '"inf"', '"x"', "[1, 2]", "{ a = 1 }",
               "true", "1e300", "1e-300", "-1e300", "[[1, 2], [3, 4]]"]


def _mutated_text(base, rng):
    """The TOML text of ``base`` with one line changed, removed or added, or the text broken."""
    lines = bundled_text(base).splitlines()
    where = [i for i, line in enumerate(lines) if _LINE.match(line)]
    i = rng.choice(where)
    kind = rng.choice(["value", "value", "scale", "delete", "extra", "broken"])
    head, value = _LINE.match(lines[i]).groups()
    if kind == "value":
        lines[i] = head + rng.choice(TEXT_VALUES)
    elif kind == "scale":
        lines[i] = head + f"{value.split('#')[0].strip()} {rng.choice(['+', '-'])} 1e300"
    elif kind == "delete":
        del lines[i]
    elif kind == "extra":
        lines.insert(i + 1, "no_such_key = 1.0")
    else:
        text = "\n".join(lines)
        cut = rng.randrange(len(text))
        return text[:cut] + rng.choice(["", "[", "= =", '"', "]]"]) + text[cut + 1:]
    return "\n".join(lines) + "\n"


def _one_clean_line(rc, err):
    """Exit 0 (nothing on stderr) or 2 (one ``invalid input`` line), never a traceback."""
    assert "Traceback" not in err, err
    assert rc in (0, EXIT_INPUT), (rc, err)
    if rc == EXIT_INPUT:
        assert len(err.strip().splitlines()) == 1, err
        assert err.startswith("pilegroup: invalid input: "), err


def test_cli_validate_mutated_files_exits_0_or_2(tmp_path, capsys):
    rng = random.Random(667)
    codes = []
    for n in range(30):
        f = tmp_path / f"m{n}.toml"
        f.write_text(_mutated_text(rng.choice(BUNDLED), rng))
        rc = main(["scenario", "validate", str(f)])
        _one_clean_line(rc, capsys.readouterr().err)
        codes.append(rc)
    assert EXIT_INPUT in codes


#: Keys of the coarse single-pile scenario the mesh test scales (by 0.5 .. 1.6).
MESH_KEYS = {"piles.diameter_m": 0.8, "piles.length_in_soil_m": 12.0, "site.size_x_m": 16.0,
             "site.depth_m": 20.0, "layers[0].thickness_m": 8.0, "numerics.mesh.size_m": 1.0,
             "numerics.mesh.growth": 1.3}


def _mesh_mutations(path, rng, count):
    """``count`` seeded ``--set`` overrides of scenario ``path`` that validate."""
    found = []
    while len(found) < count:
        keys = rng.sample(sorted(MESH_KEYS), 2)
        over = {k: MESH_KEYS[k] * rng.choice([0.5, 0.8, 1.25, 1.6]) for k in keys}
        if "numerics.mesh.growth" in over:
            over["numerics.mesh.growth"] = min(over["numerics.mesh.growth"], 2.0)
        try:
            load_scenario(path, over)
        except ScenarioError:
            continue
        found.append(over)
    return found


def test_validated_mutations_mesh_or_exit_2(small_pile, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    for n, over in enumerate(_mesh_mutations(small_pile, random.Random(11), 4)):
        out = tmp_path / f"out{n}"
        sets = [a for k, v in over.items() for a in ("--set", f"{k}={v!r}")]
        rc = main(["run", small_pile, *sets, "--stop-after", "mesh", "--out", str(out)])
        _one_clean_line(rc, capsys.readouterr().err)
        if rc == 0:  # the estimate bounds the real count from above
            cells = json.loads((out / "summary.json").read_text())["mesh"]["cells"]
            assert cells <= estimated_cells(load_scenario(small_pile, over)), (cells, over)


#: Scenarios the mesher cannot build, refused before meshing: (scenario, overrides, key named).
UNMESHABLE = [
    ("pier667", {"piles.spacing_m": [1.1, 2.5]}, "piles.grid"),  # 0.05 m to cell edge
]


def test_far_field_with_leftover_triangles_meshes(small_pile, tmp_path, monkeypatch, capsys):
    """gmsh leaves triangles in this far field; the mesher pairs them into quadrilaterals."""
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    over = {"numerics.mesh.growth": 2.0, "site.depth_m": 60.0, "numerics.mesh.n_circ_min": 12}
    sets = [a for k, v in over.items() for a in ("--set", f"{k}={v!r}")]
    rc = main(["run", small_pile, *sets, "--stop-after", "mesh", "--out", str(tmp_path / "o")])
    assert rc == 0, capsys.readouterr().err


@pytest.mark.parametrize("case", UNMESHABLE, ids=["pile-cell-edge"])
def test_unmeshable_scenarios_exit_2(case, small_pile, tmp_path, monkeypatch, capsys):
    name, over, named = case
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    sets = [a for k, v in over.items() for a in ("--set", f"{k}={v!r}")]
    rc = main(["run", name or small_pile, *sets, "--stop-after", "mesh",
               "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    _one_clean_line(rc, err)
    assert rc == EXIT_INPUT and named in err


REPRODUCTIONS = ["piles.diameter_m=1e-300", "site.depth_m=1e300", "layers[0].k_m_per_day=1e300",
                 "layers[0].e0=1e300", "layers[0].gamma_kN_per_m3=1e-300"]


@pytest.mark.parametrize("setting", REPRODUCTIONS)
def test_reproductions_exit_2_naming_the_key(setting, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    rc = main(["run", "pier667", "--set", setting, "--stop-after", "mesh",
               "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    _one_clean_line(rc, err)
    assert rc == EXIT_INPUT and setting.split("=")[0] in err


def test_pile_near_the_cap_edge_does_not_validate():
    with pytest.raises(ScenarioError, match="0.05 m to the cap edge") as info:
        load_scenario("pier667", {"cap.size_x_m": 8.1})
    assert info.value.key == "piles.grid" and "pile 1 leaves" in str(info.value)


def test_cell_count_guard_names_mesh_size():
    with pytest.raises(ScenarioError, match=r"about .* cells \(estimate\)") as info:
        load_scenario("pier667", {"site.size_x_m": 2000.0, "site.size_y_m": 2000.0,
                                  "numerics.mesh.far_field_size_m": 0.05,
                                  "numerics.mesh.size_m": 0.05})
    assert info.value.key == "numerics.mesh.size_m"


def test_bundled_estimates_are_far_below_the_limit():
    for name in BUNDLED:
        assert estimated_cells(load_scenario(name)) < 1e6


def test_every_bound_is_in_the_docs_table():
    text = DOCS.read_text()
    missing = [key for key in BOUNDS if f"`{key}`" not in text]
    assert not missing, missing
