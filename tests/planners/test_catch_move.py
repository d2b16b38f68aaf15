"""The catch move: the cup's path after the release (its coast at the catch velocity, then the brake), and the band
the catch search judges each candidate on."""

import numpy as np
import pytest

from planners.catch_move import CatchMove, cup_path
from planners.swingup_plan import TaskBounds
from trajectories.differences import derivatives

DT = 0.005  # [s]
BY, BZ = TaskBounds(0.6, 2.6, 22.0), TaskBounds(0.33, 1.5, 9.4)


def _path(coast: float) -> tuple[np.ndarray, float]:
    n = 200  # the swing-up: the pivot cruising at 0.3 m/s along y
    x, v, u = 0.3 * DT * np.arange(n), np.full(n, 0.3), np.zeros(n)
    move = CatchMove(0.5, 0.8, 0.25, -0.02, 0.4, -0.1, coast)
    return cup_path(x, v, u, DT, move, BY, BZ, settle=0.2)


@pytest.mark.parametrize("coast", [0.0, 0.06, 0.15])
def test_the_cup_keeps_its_catch_velocity_for_the_coast_then_brakes_to_rest_within_the_bounds(coast):
    path, t_reached = _path(coast)
    vel, acc, jerk = derivatives(path, DT, 3)
    k = int(round(t_reached / DT))
    assert np.allclose(path[k], (0.25, -0.02), atol=1e-6)  # the move's target, reached at t_catch
    assert abs(t_reached - 0.8) < DT
    coasting = slice(k + 2, k + int(round(coast / DT)) - 1)
    assert np.allclose(vel[coasting], (0.4, -0.1), atol=1e-9)  # constant velocity: no acceleration there
    assert np.allclose(vel[-10:], 0.0, atol=1e-9)  # at rest at the end
    # jerk-limited throughout (finite differences of a ruckig path: within the bounds plus rounding)
    for axis, b in enumerate((BY, BZ)):
        assert np.abs(acc[k:, axis]).max() <= b.a_max * 1.001
        assert np.abs(jerk[k:, axis]).max() <= b.j_max * 1.02
    # the coast moves the brake on by its length: it ends coast × velocity further on
    still, _ = _path(0.0)
    assert np.allclose(path[-1] - still[-1], (0.4 * coast, -0.1 * coast), atol=1e-9)


def test_the_search_band_judges_every_length_with_every_mass():
    from planners.catch_plan import CatchRequest, search_members
    from planners.string_model import StringModel

    members = search_members(CatchRequest(model=StringModel(0.3)))
    lengths = sorted({m.length for m in members})
    assert len(lengths) == 5 and len(members) == 15
    for ln in lengths:
        at = [m for m in members if m.length == ln]
        assert sorted(m.mass for m in at) == pytest.approx([0.0139 * 0.8, 0.0139, 0.0139 * 1.2])
        assert sorted(m.shift for m in at) == pytest.approx([-DT, 0.0, DT])
