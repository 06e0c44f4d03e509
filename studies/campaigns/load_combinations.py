"""``pilegroup combinations``: every combination of a file run as a batch, then the envelope.

The combinations file is read and every combination's scenario validated
(:mod:`pilegroup.studies.batch.combination_plan`) before anything runs. The combinations are the
cases of one batch (:func:`pilegroup.studies.batch.execute.run_batch`: MPI groups, shared queue,
failures recorded, resume, stop on SIGTERM/SIGINT/SIGUSR1), each in its run folder
``OUT/<combination>`` with ``OUT/batch.csv`` and ``OUT/batch.json``. World rank 0 then reads
the run folders and writes ``OUT/envelope.csv``, ``OUT/combination_results.csv`` and
``OUT/envelope.md`` (:mod:`pilegroup.studies.results.envelope`), also when some combinations
failed or the batch was stopped: those are listed, with their status, as not in the envelope.
Running the command again skips the combinations already complete and writes the envelope
again.
"""

from __future__ import annotations

from pathlib import Path

from mpi4py import MPI

from pilegroup.studies.batch.combination_plan import CombinationPlan, load_combination_plan
from pilegroup.studies.batch.execute import BatchResult, run_batch
from pilegroup.studies.batch.rows import BatchRow
from pilegroup.studies.results.envelope import CombinationRun
from pilegroup.studies.results.envelope_report import write_envelope


def combination_runs(plan: CombinationPlan, rows: list[BatchRow], out: Path
                     ) -> list[CombinationRun]:
    """The combinations in the file's order with their batch status, folders and loads."""
    by_name = {r["name"]: r for r in rows}
    runs = []
    for c in plan.combinations:
        row = by_name.get(c.name, {})
        runs.append(CombinationRun(c.name, out / c.name, row.get("status", "pending"),
                                   row.get("message"), dict(c.factors), plan.actions(c)))
    return runs


def intro_lines(plan: CombinationPlan) -> list[str]:
    """What ``envelope.md`` says first: the base scenario, the stage and the load cases."""
    cases = "; ".join(f"`{name}`: " + ", ".join(f"{k} = {v:g}" for k, v in case.items())
                      for name, case in plan.load_cases.items())
    return [f"Base scenario `{plan.scenario}`; the combinations set the cap actions at the end "
            f"of the load stage `{plan.stage}` (`stages[{plan.stage_index}]`): global axes, z "
            "up, moments by the right-hand rule about the scenario's reference point; "
            f"the vertical is written as `{plan.vertical_key}`.", "",
            f"Load cases (Fz_kN = -cap_load_kN): {cases}."]


def run_combinations(path: str | Path, out: str | Path, ranks_per_case: int = 1,
                     comm: MPI.Comm = MPI.COMM_WORLD, progress: bool = True,
                     memory_mb: float | None = None) -> BatchResult:
    """Run every combination of the file ``path`` not yet complete under ``out``; the envelope.

    ``memory_mb``: the memory the combinations may use on each node (:func:`run_batch`).

    Collective over ``comm``. Raises :class:`~pilegroup.errors.ScenarioError` (on every rank,
    before anything runs) for an invalid file or combination.
    """
    out = Path(out)
    plan = load_combination_plan(path)
    result = run_batch(plan.batch_plan(), out, ranks_per_case, comm, progress, memory_mb)
    if comm.rank == 0:
        write_envelope(out, combination_runs(plan, result.rows, out), plan.name,
                       intro_lines(plan))
    return result


__all__ = ["combination_runs", "intro_lines", "run_combinations"]
