// A 0.2 m cube on a 0.4 x 0.3 x 0.1 m slab, drawn with z up (the slab's top at z = 0),
// sharing the cube's base (a conforming interface); linear tetrahedra of 0.1 m.
SetFactory("OpenCASCADE");
Box(1) = {-0.2, -0.15, -0.1, 0.4, 0.3, 0.1};
Box(2) = {-0.1, -0.1, 0, 0.2, 0.2, 0.2};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
e = 1e-6;
Physical Volume("slab") = Volume In BoundingBox{-0.2-e, -0.15-e, -0.1-e, 0.2+e, 0.15+e, e};
Physical Volume("block") = Volume In BoundingBox{-0.1-e, -0.1-e, -e, 0.1+e, 0.1+e, 0.2+e};
Physical Surface("interface") = Surface In BoundingBox{-0.1-e, -0.1-e, -e, 0.1+e, 0.1+e, e};
Physical Surface("slab_bottom") = Surface In BoundingBox{-0.2-e, -0.15-e, -0.1-e, 0.2+e, 0.15+e, -0.1+e};
MeshSize{ PointsOf{ Volume{:}; } } = 0.1;
