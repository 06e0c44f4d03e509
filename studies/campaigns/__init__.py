"""Studies made of many runs and their reports: mesh sensitivity (GCI), readings, comparisons."""
