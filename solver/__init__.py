"""pilegroup.solver."""
