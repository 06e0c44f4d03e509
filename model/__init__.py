"""pilegroup.model."""
