"""Static states: the initial equilibrium, relaxation with general pairs, calibration.

:mod:`~breakwater.statics.initial` (equilibrium, bodies held to t = 0, initial
velocities), :mod:`~breakwater.statics.relaxation` (pseudo-transient relaxation with
general pairs: the stages) and :mod:`~breakwater.statics.pseudostep` (its pseudo step),
:mod:`~breakwater.statics.calibrate` (a shear modulus from a stiffness).
"""
