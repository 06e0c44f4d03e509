"""The exceptions pilegroup raises on purpose: one family under :class:`PilegroupError`.

Which class names which kind of failure:

* :class:`ScenarioError`: a scenario file or value, or a geometry specification, is invalid
  (the CLI exits with code 2);
* :class:`ConstitutiveError`: a parameter or input of a constitutive law is invalid;
* :class:`SolverError` and its subclasses: a solver input is invalid, or a run failed (the CLI
  exits with code 1);
* :class:`FitError`: a fit of parameters to data did not converge or left a parameter
  undetermined (the CLI exits with code 1);
* :class:`RunInterrupted`: a run stopped on SIGTERM, SIGINT or SIGUSR1 after saving a
  checkpoint (the CLI exits with code 128 + the signal number: 143, 130 or 138);
* :class:`FolderBusy` (a :class:`ScenarioError`): another run holds the lock of the output
  folder (exit code 2).

One exception is on purpose outside the family: :class:`OutputError`, an ``OSError`` naming
the output file that could not be written. It may be raised on one rank alone (rank 0 writes
the tables), so the CLI treats it like any unexpected error of one rank: the run ends on every
rank with exit code 1 and ``summary.json`` says ``failed``.

The input errors are also ``ValueError`` (``except ValueError`` catches them). An error about
one value names the key, the value, its unit and what is allowed, in the form of
:func:`describe`; :mod:`pilegroup.validate` builds such errors with
:meth:`PilegroupError.invalid`.
"""

from __future__ import annotations

import re
from typing import Self

#: A value shown in a message is cut to its first :data:`SHOWN_CHARS` characters when it is
#: longer than :data:`LONG_VALUE` characters (a pasted list of 10 000 numbers stays one line).
LONG_VALUE = 200
SHOWN_CHARS = 60


def shorten(value: object) -> str:
    """``value`` as a message shows it: strings quoted, a long one cut, with its length.

    E.g. ``'xxxx...'`` of 10 000 characters becomes its first 60 characters followed by
    ``... (10000 characters)``.
    """
    text = repr(value) if isinstance(value, str) else str(value)
    if len(text) <= LONG_VALUE:
        return text
    n = len(value) if isinstance(value, str) else len(text)
    return f"{text[:SHOWN_CHARS]}... ({n} characters)"


#: List keys whose entries people count from 1 (layer 1 is the top layer, pile 1 the first
#: pile, as in the mesh groups ``soil_1`` and ``pile_1``), with the word for one entry. A key
#: path keeps the TOML index, which counts from 0 as ``--set`` takes it.
ENTRY_WORDS = {"layers": "layer", "stages": "stage", "layout": "pile", "positions_m": "pile",
               "piles": "pile"}
_ENTRY = re.compile(r"(?:^|[.\s])(" + "|".join(ENTRY_WORDS) + r")\[(\d+)\]")


def entry_name(key: str) -> str:
    """The entry a key path names, counted from 1: ``layers[1].nu`` -> ``layer 2``; else ``""``.

    The first indexed list of :data:`ENTRY_WORDS` in the path decides
    (``piles.layout[0].diameter_m`` -> ``pile 1``).
    """
    m = _ENTRY.search(key)
    return f"{ENTRY_WORDS[m.group(1)]} {int(m.group(2)) + 1}" if m else ""


def describe(key: str, value: object, allowed: str, unit: str = "") -> str:
    """One line naming a rejected value, e.g. ``layers[2].nu (layer 3) = 0.55 (-): must be ...``.

    Strings are quoted; the unit is shown in brackets when given; a long value is shortened
    (:func:`shorten`). A key path into a list of layers, stages or piles is followed by the
    entry counted from 1 (:func:`entry_name`): messages count layers, stages and piles the
    same way, from 1, while the path keeps the index ``--set`` takes.
    """
    unit_txt = f" ({unit})" if unit else ""
    entry = entry_name(key)
    entry_txt = f" ({entry})" if entry else ""
    return f"{key}{entry_txt} = {shorten(value)}{unit_txt}: {allowed}"


class PilegroupError(Exception):
    """Base class of every error pilegroup raises on purpose."""

    @classmethod
    def invalid(cls, key: str, value: object, allowed: str, unit: str = "") -> Self:
        """The error for ``key = value`` (in ``unit``), which is not ``allowed``."""
        return cls(describe(key, value, allowed, unit))


class ScenarioError(PilegroupError, ValueError):
    """A scenario file or value (or a geometry specification) is invalid.

    The message always names the key (dotted path as in the TOML file), the value, its unit and
    what is allowed, e.g. ``layers[2].nu (layer 3) = 0.55 (-): must be in (0, 0.5)``; the four
    parts are also attributes, so that the loader can prefix the key with the path of its table.
    """

    def __init__(self, key: str, value: object, allowed: str, unit: str = "") -> None:
        self.key = key
        self.value = value
        self.allowed = allowed
        self.unit = unit
        super().__init__(describe(key, value, allowed, unit))

    @classmethod
    def invalid(cls, key: str, value: object, allowed: str, unit: str = "") -> Self:
        """The error for ``key = value`` (in ``unit``), which is not ``allowed``."""
        return cls(key, value, allowed, unit)


class FolderBusy(ScenarioError):
    """The output folder is locked by a run that is still going (``--out`` names it)."""


class MachineTooSmall(ScenarioError):
    """The run's estimated peak memory per rank exceeds what the machine has available.

    Raised before meshing (``studies.run.memory_check``); ``--force`` runs anyway.
    """


class PresetUnavailable(ScenarioError):
    """The scenario names a linear-solver preset this PETSc build cannot run.

    The build lacks an external package the preset needs (e.g. hypre): one line, exit code 2,
    before meshing.
    """


class OutputError(OSError):
    """An output file of a run could not be written; the message names the file and why.

    Not a :class:`PilegroupError`: it may happen on one rank alone (see the module text).
    """

    def __init__(self, path: object, exc: OSError) -> None:
        why = exc.strerror or str(exc)
        super().__init__(exc.errno, f"cannot write {path}: {why}")
        self.path = str(path)

    def __str__(self) -> str:
        return str(self.strerror)


class ConstitutiveError(PilegroupError, ValueError):
    """Invalid parameter or input of a constitutive law (or its return mapping failed)."""


class SolverError(PilegroupError, RuntimeError):
    """Base class of the solver's errors (a run failed: the CLI exits with code 1)."""


class SolverInputError(SolverError, ValueError):
    """An input of the solver is invalid; the message names the field, value, unit and range."""


class ConvergenceError(SolverError):
    """Newton or the linear solver failed (diverged, NaN, iteration limit)."""


class LinearSolveError(ConvergenceError):
    """The Krylov solver of a Newton iteration diverged or reached its iteration limit."""


class StepFailure(SolverError):
    """The adaptive stepper could not complete a step even at the minimum step size.

    ``t`` (day), ``load_factor`` and ``stage`` are those of the last equilibrium reached.
    ``run_log``: what the run did up to the failure (the stepper's ``RunLog``: accepted
    steps, rejected attempts), set by ``solver.run_stages``; ``None`` when raised elsewhere.
    """

    def __init__(self, message: str, t: float = 0.0, load_factor: float = 0.0,
                 stage: str = "", run_log: object | None = None,
                 failed_load_factor: float | None = None) -> None:
        super().__init__(message)
        self.t, self.load_factor, self.stage = t, load_factor, stage
        self.run_log = run_log
        #: the load factor of the last step tried (and failed), when the stepper knows it
        self.failed_load_factor = failed_load_factor


class CapacityReached(PilegroupError):
    """A capacity stage has found what it looks for (raised by a step callback to end it).

    Not an error of the run: the stage ends at the state reached, ``t`` (day) with
    ``load_factor``; ``reason`` says why (e.g. the settlement limit).
    """

    def __init__(self, reason: str, t: float, load_factor: float) -> None:
        super().__init__(reason)
        self.reason, self.t, self.load_factor = reason, t, load_factor


class FitError(PilegroupError):
    """A fit did not converge, or the data do not determine a fitted parameter (exit code 1)."""


class RunInterrupted(PilegroupError):
    """A run stopped at a step boundary on a signal, with a checkpoint to resume from.

    ``signal_name`` (e.g. ``"SIGTERM"``), ``signum``, ``t`` (day) and ``stage`` of the state
    reached, ``checkpoint`` (the checkpoint folder).
    """

    def __init__(self, signum: int, signal_name: str, t: float, stage: str,
                 checkpoint: str) -> None:
        super().__init__(f"interrupted by {signal_name} at t = {t:.6g} day (stage {stage}); "
                         f"checkpoint in {checkpoint}")
        self.signum, self.signal_name = signum, signal_name
        self.t, self.stage, self.checkpoint = t, stage, checkpoint


__all__ = [
    "ConstitutiveError", "ConvergenceError", "FolderBusy", "OutputError", "PilegroupError",
    "PresetUnavailable", "RunInterrupted", "ScenarioError", "SolverError", "SolverInputError",
    "StepFailure", "describe", "entry_name", "shorten",
]
