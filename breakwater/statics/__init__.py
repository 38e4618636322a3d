"""Static states: the initial equilibrium, relaxation with general pairs, calibration.

:mod:`~breakwater.statics.initial` (equilibrium, bodies held to t = 0, initial
velocities), :mod:`~breakwater.statics.relaxation` (pseudo-transient relaxation with
general pairs: the stages), :mod:`~breakwater.statics.pseudostep` (its pseudo step) and
:mod:`~breakwater.statics.release` (its bodies held up to t = 0 and their release),
:mod:`~breakwater.statics.calibrate` (a shear modulus from a stiffness).
"""
