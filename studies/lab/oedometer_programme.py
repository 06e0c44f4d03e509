"""The oedometer at one material point: a programme of load steps held over time.

No lateral strain; the vertical effective stress of each step is applied at once and held
(the vertical strain that holds it is found per step by Newton on the law's tangent
``d sigma_zz/d eps_zz``). The sample starts at ``K0`` times the first step's stress:
Soft Soil Creep and Modified Cam Clay at their ``K0nc`` (normally consolidated, or with the
law's ``OCR``/``POP`` on the K0-NC line: docs/model.md, "Soil models per layer"), the other laws
at ``1 - sin(phi)`` (Jaky; ``nu/(1 - nu)`` without a friction angle).

The programme of ``pilegroup lab`` (:func:`lab_programme`): the stress doubled from
``oedometer_start_kPa`` to ``oedometer_max_kPa``, each step held ``step_days``; a creep stage
(a step of its own at the top stress) held ``creep_days``; then halved back to the start, each
step held ``step_days``. Readings at the application and at 1, 2, 5 x 10^k times of each
step's duration from 1e-4 of it, and at its end.

Time: Soft Soil Creep creeps over a hold: its duration is integrated by the law's backward
Euler steps geometric in the time since the application, ``substeps_per_decade`` per decade
from 1e-4 of the step's duration (the readings are steps' ends too); where a step's creep has
become negligible (less than 1e-3 of ``mu* ln(ratio)`` per step, e.g. after unloading) it goes
from reading to reading. The application itself is instantaneous (elastic). The other laws are
rate independent: their hold changes nothing, and a load step is applied in ten parts (the path,
not only its end). ``fit oedometer`` replays a file's steps and times with the same function
(:func:`run_programme`).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import lambertw

from pilegroup.constitutive.cam_clay import ModifiedCamClay
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep
from pilegroup.errors import ConstitutiveError, ScenarioError
from pilegroup.studies.lab.lab_params import SoilLaw
from pilegroup.studies.lab.lab_tables import COLUMNS
from pilegroup.studies.lab.soil_tests import SoilProtocol
from pilegroup.studies.results.tables import Table

#: Relative tolerance on the held vertical stress.
HOLD_TOL = 1.0e-7
#: First sub-step of a hold, as a fraction of its duration; and of the readings.
FIRST = 1.0e-3
#: Parts of a load step of a rate-independent law.
PARTS = 10


@dataclass(frozen=True)
class LoadStep:
    """One step: the vertical effective stress held (kPa) from ``start_day``, its readings.

    ``times``: the days of its readings (``>= start_day``; at ``start_day``: just after the
    application).
    """

    stress_kPa: float
    start_day: float
    times: tuple[float, ...]


def reading_offsets(duration: float) -> tuple[float, ...]:
    """0, the 1-2-5 times in ``[FIRST duration, duration)``, and ``duration``."""
    lo = FIRST * duration * (1.0 - 1e-9)
    out = [0.0]
    for e in range(math.floor(math.log10(lo)), math.ceil(math.log10(duration)) + 1):
        out += [m * 10.0**e for m in (1.0, 2.0, 5.0)
                if lo <= m * 10.0**e < duration * (1.0 - 1e-9)]
    return (*out, duration)


def oedometer_stresses(protocol: SoilProtocol) -> np.ndarray:
    """Vertical effective stresses of the load steps: doubling up, halving down."""
    up = [protocol.oedometer_start_kPa]
    while up[-1] * 2.0 < protocol.oedometer_max_kPa * (1.0 + 1e-12):
        up.append(up[-1] * 2.0)
    if up[-1] < protocol.oedometer_max_kPa:
        up.append(protocol.oedometer_max_kPa)
    return np.array(up + up[-2::-1])


def lab_programme(protocol: SoilProtocol) -> tuple[LoadStep, ...]:
    """The steps of the lab's oedometer: loading, the creep stage, unloading (module doc)."""
    levels = oedometer_stresses(protocol)
    top = int(np.argmax(levels))
    durations = [protocol.step_days] * (len(levels) - 1)
    if protocol.creep_days > 0.0:
        levels = np.insert(levels, top + 1, levels[top])
        durations.insert(top, protocol.creep_days)
    steps, t = [LoadStep(float(levels[0]), 0.0, (0.0,))], 0.0
    for sv, d in zip(levels[1:], durations, strict=True):
        offsets = reading_offsets(d)[1 if sv == steps[-1].stress_kPa else 0:]
        steps.append(LoadStep(float(sv), t, tuple(t + u for u in offsets)))
        t += d
    return tuple(steps)


def initial_k0(law: SoilLaw) -> float:
    """``sigma'_h/sigma'_v`` of the sample at the start (module doc)."""
    if isinstance(law, SoftSoilCreep):
        return law.k0nc
    if isinstance(law, ModifiedCamClay):
        return law.k0nc()
    phi = getattr(law, "phi_deg", None)
    return 1.0 - math.sin(math.radians(phi)) if phi else law.nu / (1.0 - law.nu)


class _Sample:
    """The material point in the oedometer: its state, vertical strain and the held stress."""

    def __init__(self, law: SoilLaw, sigma_v0: float) -> None:
        k0 = initial_k0(law)
        self.law = law
        self.state = law.initial_state(1, -sigma_v0 * np.array([k0, k0, 1.0, 0.0, 0.0, 0.0]))
        self.eps_z = 0.0  # tension positive, as the law's
        self.held = sigma_v0

    def step(self, target: float, dt: float, guess: float = 0.0) -> float:
        """Strain increment holding ``sigma'_v = target`` over ``dt``; the state moves on."""
        d = np.zeros((1, 6))
        d[0, 2] = guess
        tol = HOLD_TOL * max(target, 1.0)
        for _ in range(60):
            sig, trial, tan = self.law.update(d, self.state, dt)
            r = sig[0, 2] + target
            if abs(r) <= tol:
                self.state, self.eps_z, self.held = trial, self.eps_z + d[0, 2], target
                return float(d[0, 2])
            d[0, 2] -= r / tan[0, 2, 2]
        raise ConstitutiveError(f"the oedometer did not reach sigma'_v = {target:g} kPa in 60 "
                                "Newton iterations")

    def creep(self) -> float:
        """Volumetric creep strain so far (compression positive; Soft Soil Creep)."""
        return -float(self.state["eps_c"][0, :3].sum())

    def creep_guess(self, dt: float) -> float:
        """Vertical strain increment of Soft Soil Creep over ``dt`` at the stress held.

        The backward-Euler step of the law's closed form at constant stress (rate
        ``(mu*/tau_c) exp(-x/mu*)``): ``x = mu* W(dt/tau_c)`` (Lambert's W), ``tau_c`` the
        law's creep time now; the start of Newton's iterations.
        """
        tau_c = float(self.law.creep_time(self.state["stress"], self.state["pp"])[0])
        z = min(dt / max(tau_c, 1e-300), 1e300)
        return -self.law.mu_star * float(lambertw(z).real)

    def reading(self) -> tuple[float, float, float]:
        """Vertical strain (compression positive), vertical and horizontal stress (kPa)."""
        s = self.state["stress"][0]
        return -self.eps_z, -float(s[2]), -0.5 * float(s[0] + s[1])


def _hold(sample: _Sample, step: LoadStep, per_decade: int, out: list) -> None:
    """Hold ``step``'s stress through its readings (Soft Soil Creep: over time)."""
    if not isinstance(sample.law, SoftSoilCreep):
        out += [sample.reading()] * len(step.times)
        return
    offsets = [t - step.start_day for t in step.times]
    duration = max(offsets[-1], 0.0)
    ratio = 10.0 ** (1.0 / per_decade)
    n = round(-per_decade * math.log10(FIRST))
    sub = {FIRST * duration * ratio**j for j in range(n)} if duration > 0 else set()
    readings = Counter(offsets)
    small = 1e-3 * sample.law.mu_star * math.log(ratio)
    u, slow = 0.0, False
    for g in sorted(set(readings) | {x for x in sub if x < duration}):
        if g > u and (g in readings or not slow):
            c0 = sample.creep()
            sample.step(step.stress_kPa, g - u, sample.creep_guess(g - u))
            slow = sample.creep() - c0 < small
            u = g
        if g in readings:
            out += [sample.reading()] * readings[g]


def run_programme(law: SoilLaw, steps: Sequence[LoadStep], per_decade: int = 20
                  ) -> np.ndarray:
    """The readings of ``steps`` (one row per reading time): vertical strain, sigma'_v, sigma'_h.

    The first step's stress is the start (no application); strains count from it.
    """
    sample = _Sample(law, steps[0].stress_kPa)
    parts = 1 if isinstance(law, SoftSoilCreep) else PARTS
    out: list[tuple[float, float, float]] = []
    for step in steps:
        prev = sample.held
        if step.stress_kPa != prev:
            for k in range(1, parts + 1):
                sample.step(prev + (step.stress_kPa - prev) * k / parts, 0.0)
        _hold(sample, step, per_decade, out)
    return np.array(out, dtype=float).reshape(-1, 3)


def oedometer_test(law: SoilLaw, e0: float, protocol: SoilProtocol) -> Table:
    """The lab's oedometer (:func:`lab_programme`); ``e0`` the initial void ratio."""
    if not 0.0 < e0 < 10.0:
        raise ScenarioError("--e0", e0, "must be a void ratio in (0, 10)")
    steps = lab_programme(protocol)
    rows = run_programme(law, steps, protocol.substeps_per_decade)
    number = np.concatenate([[k] * len(s.times) for k, s in enumerate(steps)])
    time = np.concatenate([s.times for s in steps])
    cols = (number, time, rows[:, 0], rows[:, 1], rows[:, 2], e0 - (1.0 + e0) * rows[:, 0])
    return {c: np.asarray(v, dtype=float) for c, v in zip(COLUMNS["oedometer"], cols,
                                                           strict=True)}


__all__ = ["FIRST", "HOLD_TOL", "LoadStep", "initial_k0", "lab_programme",
           "oedometer_stresses", "oedometer_test", "reading_offsets", "run_programme"]
