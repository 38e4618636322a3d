"""The compiled reach of a general pair's search: which master facets a search may skip.

:func:`mark_near` marks the master facets near the slave surface, :func:`beyond_reach`
tells whether every other one is beyond the search radius (then the search on the
marked ones is the whole search: :func:`breakwater.contact.searchkernels.search`, which
re-exports both). 2-D, facets of 2 or 3 nodes.
"""

from __future__ import annotations

import numpy as np

from breakwater.common.jit import kernel

__all__ = ["beyond_reach", "mark_near"]


@kernel
def mark_near(xs, xm, reach, near):  # type: ignore[no-untyped-def]
    """Mark the master facets whose node box comes within ``reach`` of a slave facet's.

    ``xs``, ``xm``: the current nodes; ``near``: the marks (changed in place).

    Returns:
        How many were newly marked.
    """
    s_lo, s_hi = _boxes(xs)
    m_lo, m_hi = _boxes(xm)
    added = 0
    for f in range(xm.shape[0]):
        if near[f]:
            continue
        for s in range(xs.shape[0]):
            if (m_lo[f, 0] <= s_hi[s, 0] + reach and m_hi[f, 0] >= s_lo[s, 0] - reach
                    and m_lo[f, 1] <= s_hi[s, 1] + reach and m_hi[f, 1] >= s_lo[s, 1] - reach):
                near[f] = True
                added += 1
                break
    return added


@kernel
def beyond_reach(xs, xm, use, radius, tol):  # type: ignore[no-untyped-def]
    """Whether every master facet not in ``use`` is beyond ``radius`` of the slave facets.

    Per coordinate, the node boxes grown to hold the curves (a quadratic facet leaves
    its node box by at most its sag c = |½(x₀ + x₁) − x₂|; :func:`near`'s margin, with
    the projections' ``tol`` beyond the master's ends): a facet whose box is more than
    ``radius`` from every slave facet's can hold no projection of a slave point, and its
    vertices project onto no slave facet.

    Args:
        xs: The slave facets' current nodes.
        xm: The master's.
        use: The master facets in use.
        radius: The search radius.
        tol: A projection at ``|ξ| ≤ 1 + tol`` is inside its master facet.
    """
    s_lo, s_hi = _curve_boxes(xs, 1e-9)
    m_lo, m_hi = _curve_boxes(xm, tol)
    for f in range(xm.shape[0]):
        if use[f]:
            continue
        for s in range(xs.shape[0]):
            if (m_lo[f, 0] <= s_hi[s, 0] + radius and m_hi[f, 0] >= s_lo[s, 0] - radius
                    and m_lo[f, 1] <= s_hi[s, 1] + radius
                    and m_hi[f, 1] >= s_lo[s, 1] - radius):
                return False
    return True


@kernel
def _curve_boxes(x, tol):  # type: ignore[no-untyped-def]
    """Each facet's box holding its curve for ``|ξ| ≤ 1 + tol`` (:func:`near`'s margin)."""
    lo, hi = np.empty((x.shape[0], 2)), np.empty((x.shape[0], 2))
    for f in range(x.shape[0]):
        for d in range(2):
            x0, x1 = x[f, 0, d], x[f, 1, d]
            a, b = min(x0, x1), max(x0, x1)
            half, c = 0.5 * abs(x1 - x0), 0.0
            if x.shape[1] == 3:
                x2 = x[f, 2, d]
                a, b = min(a, x2), max(b, x2)
                c = abs(0.5 * (x0 + x1) - x2)
            margin = c + tol * (half + 3 * c)
            lo[f, d], hi[f, d] = a - margin, b + margin
    return lo, hi


@kernel
def _boxes(x):  # type: ignore[no-untyped-def]
    """Each facet's node box: lower and upper corners, ``(F, 2)`` each."""
    lo, hi = np.empty((x.shape[0], 2)), np.empty((x.shape[0], 2))
    for f in range(x.shape[0]):
        for d in range(2):
            lo[f, d], hi[f, d] = x[f, 0, d], x[f, 0, d]
            for a in range(1, x.shape[1]):
                lo[f, d], hi[f, d] = min(lo[f, d], x[f, a, d]), max(hi[f, d], x[f, a, d])
    return lo, hi
