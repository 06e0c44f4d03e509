"""Newton gives up a step that alternates between two states (solver/newton.py ``cycling``).

The sequences are the largest residual over its tolerance per iteration, as traced in
``pier667_downdrag`` at h = 0.1 m (day 256.8, a 25.6-day step that failed after 15 iterations
and was cut, and day 42.8, a step that converged after 10 slow iterations).
"""

from pilegroup.solver.newton import cycling

FAILED = [316.0, 188.0, 48.1, 38.6, 2.06, 8.50, 1.15, 8.86, 1.18, 8.83, 1.18, 8.83, 1.18, 8.83,
          1.18, 8.83]
SLOW = [381.0, 231.0, 20.8, 18.5, 13.8, 12.1, 16.3, 1.05, 1.89, 0.969]


def first_cycle(ratios):
    return next((k for k in range(1, len(ratios) + 1) if cycling(ratios[:k])), None)


def test_a_two_state_cycle_is_found_after_two_repeats():
    assert first_cycle(FAILED) == 9  # after 8 Newton iterations instead of the 15 of the limit


def test_slow_or_monotone_convergence_is_not_a_cycle():
    assert first_cycle(SLOW) is None
    assert first_cycle([1.10, 1.08, 1.06, 1.04, 1.02, 1.01, 1.005]) is None  # creeping down
    assert first_cycle([5.0, 0.9, 5.0, 0.9, 5.0]) is None  # the lower state is converged
