// h_tet_slab.geo drawn in millimetres (gmsh scales it by 1000): a 0.8 m slab as 800 m.
Merge "h_tet_slab.geo";
Mesh.ScalingFactor = 1000;
