"""Workflows on top of the solver, one concern per subpackage (docs/architecture.md).

``results`` (file contract) -> ``report`` (figures) -> ``run`` (one run) -> ``batch``,
``verification`` -> ``campaigns`` (studies of many runs) -> ``bench`` -> ``cli``.
"""
