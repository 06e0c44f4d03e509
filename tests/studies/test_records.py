"""The run's JSON summaries hold exactly the fields their types document."""

import json
import typing

from pilegroup.studies.results.records import JobSummary, MeshRecord, RunSummary


def _keys(td) -> set[str]:
    return set(typing.get_type_hints(td))


def test_summaries_hold_the_documented_fields(small_pile_run):
    job = json.loads((small_pile_run / "summary.json").read_text())
    solver = json.loads((small_pile_run / "summary_solver.json").read_text())
    assert set(job) <= _keys(JobSummary), set(job) - _keys(JobSummary)
    assert job["status"] == "complete" and set(job["mesh"]) == _keys(MeshRecord)
    for summary in (job["solver"], solver):
        assert set(summary) <= _keys(RunSummary), set(summary) - _keys(RunSummary)
    # what every complete run reports
    assert {"complete", "dofs", "symmetry", "settlement_m", "neutral_plane", "steps",
            "newton_iterations", "history"} <= set(solver)
    assert solver["complete"] is True
    assert set(solver["symmetry"]) == {"model", "reason"}
