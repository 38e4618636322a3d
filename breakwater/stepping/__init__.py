"""Time stepping: the GN22 scheme, its Newton solvers and the step-size control.

:mod:`~breakwater.stepping.gn22` (the scheme), :mod:`~breakwater.stepping.stepsolver`
(the protocol of a step's solver), :mod:`~breakwater.stepping.solver` (Newton with
PETSc SNES on the full residual: the reference path), the fast path (bulk factorised
once per Δt, Newton on the contact surfaces only): :mod:`~breakwater.stepping.condensed`
(its solver), :mod:`~breakwater.stepping.bulk` (M, K, loads, the predictor),
:mod:`~breakwater.stepping.factorisations` (A, X = A⁻¹E and S per Δt),
:mod:`~breakwater.stepping.interface` (the interface unknowns, f_c on them),
:mod:`~breakwater.stepping.interfacenewton` (the SNES on them); and
:mod:`~breakwater.stepping.stepsize` (cut-back).
"""
