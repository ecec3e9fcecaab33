"""κ at one configuration on the κ tracker's engine (metrics/tracker/extremes.py)."""

import numpy as np
import pytest
from closed_forms import rod_chain_gim, straight_chain_extreme_eigenvalues

from gimwatch.denoc import DenocModel
from gimwatch.errors import ConditioningError
from gimwatch.metrics.equilibrated import ScaledProducts, ScaledState, equilibrated_extremes
from gimwatch.metrics.linear_analysis import chain_configurations
from gimwatch.metrics.tracker import extreme_eigenvalues
from gimwatch.model.chains import chain_spec


@pytest.mark.parametrize("n", [1_000, 10_000])
def test_the_clustered_straight_chain_is_certified_and_bracketed(n):
    # the closed-form pencil (tests/closed_forms.py, bisection on a banded reformulation), not
    # DeNOC: the certified bracket [κ, κ(1 + e)] holds it (the plain Lanczos this replaced was
    # off by 2e-7 at n = 10,000, uncertified)
    lambda_min, lambda_max = straight_chain_extreme_eigenvalues(n)
    exact = lambda_max / lambda_min
    found = extreme_eigenvalues(DenocModel.from_chain(chain_spec(n)).state(np.zeros(n)), rtol=1e-9)
    assert found.certified and found.error_estimate == pytest.approx(2e-9, rel=1e-6)
    assert found.kappa * (1 - 1e-12) <= exact <= found.kappa * (1 + found.error_estimate + 1e-12)
    assert found.products < 200  # shift-invert: the old plain Lanczos took 510 and 2,670


def test_the_equilibrated_operators_match_numpy():
    # κ_S of S = D^-1/2 M D^-1/2 from S·x and S⁻¹·y against eigvalsh of the closed-form M's S
    n = 30
    q = chain_configurations(chain_spec(n), 1, seed=4)[0]
    state = DenocModel.from_chain(chain_spec(n)).state(q)
    low, high = equilibrated_extremes(rod_chain_gim(q))
    found = extreme_eigenvalues(ScaledState(state), rtol=1e-12)
    assert found.kappa == pytest.approx(high / low, rel=1e-9)
    assert not found.certified  # DeNOC's factor shifts by a multiple of 1 only: no certificate


def test_scaled_products_decline_a_certificate_they_cannot_give():
    lean = DenocModel.from_chain(chain_spec(5)).lean()
    products = ScaledProducts(lean, lean.gim_diagonal)
    with pytest.raises(ConditioningError, match="before configure"):
        products.shifted_inertia(1.0)
    products.configure(np.zeros(5))
    assert not products.shifts_by_diagonal
    assert products.shifted_inertia(1.0) is None
