"""Many runs of one base scenario on groups of MPI ranks: the plan, the queue, the rows."""
