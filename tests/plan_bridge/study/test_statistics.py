"""The study's intervals and tests: textbook values, and SciPy as an oracle where installed."""

from __future__ import annotations

import random

import pytest

from plan_bridge.study.statistics import (
    fisher_exact,
    holm,
    mann_whitney_u,
    median_ci,
    newcombe,
    wilson,
)


def test_fisher_exact_gives_the_tea_tasting_p_value() -> None:
    # Fisher's lady tasting tea: 3 of 4 cups right each way, two-sided p = 34/70.
    assert fisher_exact(3, 1, 1, 3) == pytest.approx(34 / 70)


def test_fisher_exact_is_one_for_equal_groups_and_small_for_opposite_ones() -> None:
    assert fisher_exact(10, 10, 10, 10) == pytest.approx(1.0)
    assert fisher_exact(20, 0, 0, 20) < 1e-10
    assert fisher_exact(0, 0, 0, 0) == 1.0


def test_fisher_exact_rejects_negative_cells() -> None:
    with pytest.raises(ValueError, match="counts >= 0"):
        fisher_exact(-1, 2, 3, 4)


def test_mann_whitney_u_counts_pairs_and_ties_count_half() -> None:
    u, _ = mann_whitney_u([1.0, 2.0, 3.0], [4.0, 5.0])
    assert u == 0.0
    u, _ = mann_whitney_u([1.0, 5.0], [1.0, 2.0])
    assert u == 2.5  # 5 beats both, 1 ties with 1


def test_mann_whitney_u_p_value_is_one_when_every_value_ties() -> None:
    assert mann_whitney_u([2.0, 2.0], [2.0, 2.0, 2.0]) == (3.0, 1.0)


def test_mann_whitney_u_rejects_an_empty_sample() -> None:
    with pytest.raises(ValueError, match="both samples"):
        mann_whitney_u([], [1.0])


def test_mann_whitney_u_separated_samples_have_a_small_p_value() -> None:
    _, p = mann_whitney_u([float(v) for v in range(20)], [float(v) for v in range(100, 120)])
    assert p < 1e-6


def test_statistics_agree_with_scipy() -> None:
    stats = pytest.importorskip("scipy.stats")
    rng = random.Random(7)
    for _ in range(40):
        n1, n2 = rng.randint(1, 25), rng.randint(1, 25)
        s1, s2 = rng.randint(0, n1), rng.randint(0, n2)
        expected = stats.fisher_exact([[s1, n1 - s1], [s2, n2 - s2]]).pvalue
        assert fisher_exact(s1, n1 - s1, s2, n2 - s2) == pytest.approx(expected, rel=1e-9)
        # rounded values make ties, as simulated times do
        x = [round(rng.expovariate(1.0), 1) for _ in range(n1)]
        y = [round(rng.expovariate(0.7), 1) for _ in range(n2)]
        if len(set(x + y)) == 1:
            continue
        ref = stats.mannwhitneyu(x, y, alternative="two-sided", method="asymptotic")
        u, p = mann_whitney_u(x, y)
        assert u == pytest.approx(ref.statistic)
        assert p == pytest.approx(ref.pvalue, rel=1e-9)


def test_wilson_interval_brackets_the_proportion() -> None:
    low, high = wilson(18, 20)
    assert 0.68 < low < 0.9 < high < 0.98
    assert wilson(0, 0) == (0.0, 0.0)


def test_newcombe_interval_of_a_difference_excludes_zero_only_for_a_clear_difference() -> None:
    low, high = newcombe(20, 20, 2, 20)
    assert 0.5 < low < 0.9 < high <= 1.0
    low, high = newcombe(10, 20, 11, 20)
    assert low < 0 < high


def test_median_ci_uses_order_statistics_with_95_percent_coverage() -> None:
    values = [float(v) for v in range(1, 21)]
    # n = 20: the 6th and 15th smallest values (coverage 95.9%)
    assert median_ci(values) == (10.5, 6.0, 15.0)
    assert median_ci([3.0, 1.0, 2.0]) == (2.0, 1.0, 3.0)
    with pytest.raises(ValueError, match="no values"):
        median_ci([])


def test_holm_adjusts_in_step_down_order_and_keeps_monotonicity() -> None:
    assert holm([0.01, 0.04, 0.03]) == pytest.approx([0.03, 0.06, 0.06])
    assert holm([]) == []
