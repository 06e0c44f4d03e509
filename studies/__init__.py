"""pilegroup.studies."""
