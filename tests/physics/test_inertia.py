"""Low-frequency effective roll inertia of a closed, full tank against Stokes-Joukowski."""
import pytest

from jaxslosh.liquid.modes import effective_roll_inertia

# Stokes-Joukowski: effective / frozen roll inertia of an inviscid liquid filling a rectangle
SJ = {1.0: 0.1565, 2.0: 0.45}


@pytest.mark.parametrize("breadth,aspect", [(4.0, 1.0), (8.0, 2.0)])
def test_default_form_does_not_spin_up(breadth, aspect):
    I_eff, _, I_frozen = effective_roll_inertia((2.0, breadth, 4.0), (2, int(4 * breadth), 16 if aspect == 1 else 8))
    assert abs(I_eff / I_frozen / SJ[aspect] - 1) < 0.02, I_eff / I_frozen


def test_relative_rotation_penalty_and_paper_form_turn_the_liquid_with_the_tank():
    """Penalising the relative rotation (or the paper's p0 |grad u|^2) gives the frozen inertia."""
    I_rel, I_fd, I_frozen = effective_roll_inertia((2.0, 4.0, 4.0), (2, 8, 8), absolute_rotation=False)
    assert abs(I_rel / I_fd - 1) < 1e-3
    I_paper, _, _ = effective_roll_inertia((2.0, 4.0, 4.0), (2, 8, 8), element="paper")
    assert abs(I_paper / I_frozen - 1) < 1e-2
