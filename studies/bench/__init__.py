"""Benchmarks: commands that measure cost against size or error and print tables (never tests)."""
