"""Figures and Markdown of one run folder: plots, the 3D view, a scenario's published values."""
