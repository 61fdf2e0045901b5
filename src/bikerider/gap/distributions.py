"""The two tail probabilities the gap diagnosis needs, from :mod:`scipy.special` directly.

``scipy.stats`` computes ``chi2.sf``, ``chi2.ppf`` and ``f.sf`` with these same special functions
(the values are identical), but importing it takes about half a second (a third of a short
diagnosis's start-up), for three formulas.
"""

from __future__ import annotations

import numpy as np
from scipy.special import chdtrc, fdtrc, gammaincinv


class chi2:  # noqa: N801 - named as scipy.stats.chi2, which it stands in for
    """The chi-square distribution with ``k`` degrees of freedom (upper tail and quantile)."""

    @staticmethod
    def sf(x, k):
        """``P(X > x)`` (1 for ``x <= 0``)."""
        return chdtrc(k, np.maximum(x, 0.0))

    @staticmethod
    def ppf(p, k):
        """The ``p``-quantile."""
        return 2 * gammaincinv(np.asarray(k, dtype=float) / 2, p)


class f:  # noqa: N801 - named as scipy.stats.f
    """Fisher's F distribution with ``d1`` and ``d2`` degrees of freedom (upper tail)."""

    @staticmethod
    def sf(x, d1, d2):
        """``P(X > x)`` (1 for ``x <= 0``)."""
        return fdtrc(d1, d2, np.maximum(x, 0.0))
