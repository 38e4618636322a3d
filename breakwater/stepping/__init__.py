"""Time stepping: the GN22 scheme, its Newton solvers and the step-size control.

:mod:`~breakwater.stepping.gn22` (the scheme), :mod:`~breakwater.stepping.solver`
(Newton with PETSc SNES on the full residual), :mod:`~breakwater.stepping.bulk` and
:mod:`~breakwater.stepping.condensed` (the fast path: bulk factorised once per Δt,
Newton on the contact surfaces only), :mod:`~breakwater.stepping.stepsize` (cut-back).
"""
