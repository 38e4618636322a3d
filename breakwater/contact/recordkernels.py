"""A general pair's outputs at one state in one compiled pass (the history row, the ledger).

An accepted step's outputs read a general pair's state several times: the history row's
resultant, contact length and largest penetration
(:meth:`~breakwater.contact.general.SurfaceContact.measure`) and the ledger's penalty
energy and friction power (:meth:`~breakwater.contact.general.SurfaceContact.energies`).
Through the NumPy law (:mod:`forms.contact`) each is a dozen small array operations on
arrays of a hundred points; :func:`pair_record` sums them all from the residual's
points and the friction's nodal forces (what the Newton's last evaluation found) in
one loop. The integrands are the law's, written out: the penalty energy density
``½ p²/ε_n`` with ``p = ε_n ⟨−g_n⟩₊`` (:meth:`forms.PenaltyContact.energy`) and the
friction power ``μ λ_k |v_T|²/sqrt(|v_T|² + χ²)`` (:meth:`forms.RegularisedCoulomb.power`
with the nodal normal force λ_k for the pressure); ``tests/test_recordkernels.py``
checks them against the law.
"""

from __future__ import annotations

import math

import numpy as np

from breakwater.common.jit import kernel

__all__ = ["RECORD", "pair_record"]

RECORD = ("energy", "power", "contact_length", "penetration", "normal_x", "normal_y",
          "friction_x", "friction_y")
"""The entries of :func:`pair_record`'s array, in order."""


@kernel
def pair_record(index, gap, all_weight, forces, ns, eps, k, lam, v_T, friction, mu,
                chi):  # type: ignore[no-untyped-def]
    """The pair's outputs at one state (:data:`RECORD`; compiled).

    Args:
        index: The points with a projection, among all the integration points.
        gap: Their g_n.
        all_weight: Every integration point's weight (reference length).
        forces: The projected points' nodal forces ``(K, ns + nm, 2)``: the slave's
            first (``−N_s t w``, the residual's sign).
        ns: The nodes of a slave facet.
        eps: ε_n.
        k: The slave nodes with a friction force.
        lam: Every slave node's normal force λ.
        v_T: Their tangential slip velocities ``(len(k), 2)``.
        friction: Their friction forces ``(len(k), 2)``.
        mu: μ.
        chi: χ.

    Returns:
        Penalty energy ``Σ w ½ ε_n ⟨−g_n⟩₊²``, friction power, contact length (the
        weight where g_n ≤ 0), largest ⟨−g_n⟩₊ (0: none), the normal and friction
        resultants on the slave.
    """
    out = np.zeros(8)
    for j in range(len(index)):
        g = gap[j]
        if g <= 0.0:
            w = all_weight[index[j]]
            p = eps * -g
            out[0] += w * (0.5 * p * p / eps)
            out[2] += w
            out[3] = max(out[3], -g)
    for j in range(forces.shape[0]):
        for a in range(ns):
            out[4] -= forces[j, a, 0]
            out[5] -= forces[j, a, 1]
    for i in range(len(k)):
        vx, vy = v_T[i, 0], v_T[i, 1]
        vv = vx * vx + vy * vy
        out[1] += mu * lam[k[i]] * vv / math.sqrt(vv + chi * chi)
        out[6] += friction[i, 0]
        out[7] += friction[i, 1]
    return out
