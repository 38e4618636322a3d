"""Storms: wave trains, each wave's pressure history, and the rigid-block sliding model.

Performance-based design of a caisson breakwater (Shimosako & Takahashi 1994, 1999;
Goda & Takagi 2000) drives the caisson wave by wave through a storm. This subpackage holds
what does not need a finite-element model (plain Python and NumPy):

- :mod:`breakwater.storms.waves`: the data passed between the parts: a :class:`Wave`
  (height, period, start), a :class:`WaveTrain`, the :class:`Site` (Goda's geometry of
  the breakwater and the water), and a :class:`WaveLoad` (one wave's front-pressure shape
  and the time histories of p₁ and of the uplift p_u).
- :mod:`breakwater.storms.seastate`: a :class:`~breakwater.storms.seastate.SeaState` and
  its waves (Rayleigh heights capped by breaking), a user's wave-by-wave table.
- :mod:`breakwater.storms.waveforce`: one wave's Goda(–Takahashi) pressures over time
  and their resultants.
- :mod:`breakwater.storms.rigid`: the rigid-block sliding model (Shimosako & Takahashi).
- :mod:`breakwater.storms.montecarlo`: the expected sliding distance over storms.
"""

from breakwater.storms.waves import Site, Wave, WaveLoad, WaveTrain

__all__ = ["Site", "Wave", "WaveLoad", "WaveTrain"]
