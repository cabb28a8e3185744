"""Intervals and tests for the study's comparisons, in plain Python (no SciPy needed).

- :func:`wilson`: 95% score interval of a success rate.
- :func:`newcombe`: interval of the difference of two success rates (Newcombe's
  hybrid score method, built from the two Wilson intervals).
- :func:`fisher_exact`: two-sided p-value of Fisher's exact test on a 2x2 table
  (success/failure of two approaches). Exact integer arithmetic: the cells are small.
- :func:`mann_whitney_u`: U statistic and two-sided p-value of the Mann-Whitney U
  test, normal approximation with tie correction and continuity correction (what
  SciPy calls ``method="asymptotic"``).
- :func:`median_ci`: median with a distribution-free interval from order statistics.
- :func:`holm`: Holm's step-down adjustment of a family of p-values.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["fisher_exact", "holm", "mann_whitney_u", "median_ci", "newcombe", "wilson"]

Z95 = 1.959963984540054


def wilson(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """95% Wilson score interval of a proportion; ``(0, 0)`` when there are no runs."""
    if n == 0:
        return (0.0, 0.0)
    if not 0 <= successes <= n:
        raise ValueError(f"wilson: successes must be between 0 and n={n}, got {successes}")
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def newcombe(s1: int, n1: int, s2: int, n2: int) -> tuple[float, float]:
    """95% interval of ``s1/n1 - s2/n2`` (Newcombe 1998, method 10)."""
    if n1 == 0 or n2 == 0:
        raise ValueError("newcombe: both groups need at least one run")
    p1, p2 = s1 / n1, s2 / n2
    l1, u1 = wilson(s1, n1)
    l2, u2 = wilson(s2, n2)
    d = p1 - p2
    low = d - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2)
    high = d + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2)
    return (max(-1.0, low), min(1.0, high))


def fisher_exact(a: int, b: int, c: int, d: int) -> float:
    """Two-sided p-value of Fisher's exact test on the table ``[[a, b], [c, d]]``.

    Sums the probabilities of every table with the same margins that is at most as
    likely as the observed one (the usual two-sided definition, as in R and SciPy).
    """
    if min(a, b, c, d) < 0:
        raise ValueError(f"fisher_exact: cells must be counts >= 0, got {[a, b, c, d]}")
    row1, row2, col1 = a + b, c + d, a + c
    n = row1 + row2
    if n == 0:
        return 1.0
    denominator = math.comb(n, col1)
    low, high = max(0, col1 - row2), min(col1, row1)
    weights = {x: math.comb(row1, x) * math.comb(row2, col1 - x) for x in range(low, high + 1)}
    observed = weights[a]
    # Integer weights compare exactly; the relative slack matches R's 1e-7 for ties
    # that only floating point would split.
    limit = observed * (1 + 1e-7)
    total = sum(w for w in weights.values() if w <= limit)
    return min(1.0, total / denominator)


def _ranks(values: Sequence[float]) -> tuple[list[float], float]:
    """Mid-ranks (1-based) of ``values`` and the tie term sum(t^3 - t)."""
    order = sorted(range(len(values)), key=lambda i: values[i])
    ranks = [0.0] * len(values)
    ties = 0.0
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and values[order[j + 1]] == values[order[i]]:
            j += 1
        mid = (i + j) / 2 + 1
        for k in range(i, j + 1):
            ranks[order[k]] = mid
        t = j - i + 1
        ties += t**3 - t
        i = j + 1
    return ranks, ties


def mann_whitney_u(x: Sequence[float], y: Sequence[float]) -> tuple[float, float]:
    """U of ``x`` against ``y`` and the two-sided p-value (normal approximation).

    The variance is corrected for ties and a continuity correction of 0.5 is applied.
    Raises ``ValueError`` when a sample is empty (there is nothing to compare).
    """
    n1, n2 = len(x), len(y)
    if n1 == 0 or n2 == 0:
        raise ValueError(f"mann_whitney_u: both samples need values (got {n1} and {n2})")
    ranks, ties = _ranks([*x, *y])
    u1 = sum(ranks[:n1]) - n1 * (n1 + 1) / 2
    n = n1 + n2
    mean = n1 * n2 / 2
    variance = n1 * n2 / 12 * ((n + 1) - ties / (n * (n - 1))) if n > 1 else 0.0
    if variance <= 0:
        return (u1, 1.0)  # every value tied: no evidence of a difference
    z = (abs(u1 - mean) - 0.5) / math.sqrt(variance)
    p = math.erfc(max(z, 0.0) / math.sqrt(2))
    return (u1, min(1.0, p))


def median_ci(values: Sequence[float]) -> tuple[float, float, float]:
    """Median and a distribution-free 95% interval from order statistics.

    The interval is ``(x[j], x[n-1-j])`` for the largest ``j`` whose binomial(n, 1/2)
    coverage is still at least 95%. With fewer than 6 values no such pair exists and
    the interval is the range of the values (its coverage is below 95%).
    """
    if not values:
        raise ValueError("median_ci: no values")
    xs = sorted(values)
    n = len(xs)
    median = (xs[(n - 1) // 2] + xs[n // 2]) / 2
    j = 0
    # coverage of (x[j], x[n-1-j]) is 1 - 2 * P(B <= j) with B ~ Binomial(n, 1/2)
    tail = 0.0
    for k in range(n // 2):
        tail += math.comb(n, k) / 2**n
        if 1 - 2 * tail < 0.95:
            break
        j = k
    return (median, xs[j], xs[n - 1 - j])


def holm(pvalues: Sequence[float]) -> list[float]:
    """Holm-adjusted p-values, in the order given."""
    m = len(pvalues)
    order = sorted(range(m), key=lambda i: pvalues[i])
    adjusted = [0.0] * m
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, min(1.0, (m - rank) * pvalues[i]))
        adjusted[i] = running
    return adjusted
