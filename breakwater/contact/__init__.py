"""Contact pairs: the conforming node-to-node interface and general (non-matching) pairs.

- conforming pairs: :mod:`~breakwater.contact.conforming` (node pairs),
  :mod:`~breakwater.contact.nodal` (their forces on nodal arrays),
  :mod:`~breakwater.contact.slipguard` (Newton's slip guard);
- general pairs: :mod:`~breakwater.contact.surfaces` (settings and facets),
  :mod:`~breakwater.contact.projection` (closest-point projection),
  :mod:`~breakwater.contact.pointkernels` (nodal forces of contact points),
  :mod:`~breakwater.contact.general` (the pair itself),
  :mod:`~breakwater.contact.penetration` (what the search cannot see);
- 3-D general pairs' building blocks (not yet used by a pair, issue 25):
  :mod:`~breakwater.contact.projection3d` (closest-point projection onto triangular
  faces; :mod:`~breakwater.contact.searchkernels3d` compiled),
  :mod:`~breakwater.contact.clip3d` (mortar segmentation of the slave surface).

The contact law itself is written once, in UFL and NumPy, in :mod:`breakwater.forms.contact`.
"""
