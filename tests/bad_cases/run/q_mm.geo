// q_conforming.geo's block on its base drawn in millimetres: a 2 x 1 m block on a
// 4 x 1 m base whose coordinates are mm (gmsh scales the 0.2 m block by 10000).
Merge "q_conforming.geo";
Mesh.ScalingFactor = 10000;
