"""The ``pilegroup`` command line: argument parsing, exit codes, one-line errors."""
