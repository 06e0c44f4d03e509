"""pilegroup.constitutive."""
