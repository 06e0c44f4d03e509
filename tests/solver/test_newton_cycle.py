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


# ---------------------------------------------------------------- the alternate tolerance
#: Largest residual / tolerance per iteration of a Pier 667 loading step at h = 0.1 m (day 0.15,
#: 0.2 day) that chattered above the tolerance until the iteration limit and was cut.
CHATTER = [5.86e6, 860.0, 523.0, 746.0, 22.9, 41.7, 22.6, 22.8, 3.55, 28.0, 26.8, 3.48, 57.5,
           3.56, 28.5, 3.44]


class _Scripted:
    """A step problem whose residual follows a script (block 0, tolerance 1 with the options)."""

    block_count, u_blocks, plate, plate_block = 1, [0], None, None

    def __init__(self, ratios):
        from petsc4py import PETSc

        self.ratios, self.k = list(ratios), 0
        self.x, self.b, self.dx = (PETSc.Vec().createSeq(1) for _ in range(3))
        self.x.set(1.0)

    def set_step(self, dt, load_factor):
        self.k = 0

    def residual_state(self, load_factor):
        import numpy as np

        r = self.ratios[min(self.k, len(self.ratios) - 1)]
        self.k += 1
        return np.array([r]), 0.0

    def force_scales(self):
        return [0.0]

    def assemble_jacobian(self, force=False):
        return True

    def solve_linear(self, rhs, sol, tol=None):
        sol.set(1e-3)
        return 1

    def block_norms(self, vec):
        import numpy as np

        return np.array([vec.norm()])

    def x_to_fields(self, vec):
        pass


def _solve(ratios, **options):
    from pilegroup.solver.inputs import NewtonOptions
    from pilegroup.solver.newton import NewtonSolver

    # rtol 0, atol 1: the residual is its own ratio; no line search (the script ignores x)
    nw = NewtonOptions(rtol=0.0, atol=1.0, line_search=0, **options)
    return NewtonSolver(_Scripted(ratios), nw).solve(0.1, 1.0)


def test_a_chattering_step_is_accepted_by_the_alternate_tolerance_from_its_iteration():
    info = _solve(CHATTER)
    assert info.converged and info.alternate and info.newton_its == 4  # 22.9 <= 100 at it 4
    cut = _solve(CHATTER, alt_factor=3.0)  # below every value of the band: the step fails
    assert not cut.converged and not cut.alternate


def test_the_alternate_tolerance_waits_for_its_iteration_and_the_strict_one_does_not():
    early = [1e4, 50.0, 20.0, 0.5]  # converged at iteration 3, strictly
    info = _solve(early)
    assert info.converged and not info.alternate and info.newton_its == 3
    late = [1e4, 50.0, 20.0, 35.0, 25.0, 40.0, 22.0, 33.0, 27.0, 31.0]  # no 2-cycle
    waited = _solve(late, alt_after=9)
    assert waited.converged and waited.alternate and waited.newton_its == 9
