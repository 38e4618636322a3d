"""Loads as functions of time and space: pulse signals, traction fields, Goda's pressure.

Pure Python and UFL only; the case file's ``[loads.*]`` tables
(:mod:`breakwater.casefile.loads`) turn them into the model's surface loads.
"""
