"""The energy ledger: every joule of a run accounted for, step by step.

:mod:`~breakwater.energy.ledger` (the ledger), :mod:`~breakwater.energy.bulkenergy`
(kinetic and strain energy, damping), :mod:`~breakwater.energy.dissipation` (what
GN22 itself dissipates per step).
"""
