"""pilegroup.geometry."""
