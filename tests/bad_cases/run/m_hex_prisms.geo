// m_prisms.geo with the block's face recombined: hexahedra in the block, prisms in the
// slab.
Merge "m_prisms.geo";
Recombine Surface{2};
