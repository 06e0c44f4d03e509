"""Figures and Markdown of one run folder: plots, the 3D view, the paper's reported values."""
