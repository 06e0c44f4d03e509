"""One run: scenario -> mesh -> problem -> stages -> exports, with its probes and checkpoints."""
