// A 0.2 m cube on a 0.4 x 0.1 x 0.3 m slab, sharing the cube's base (BooleanFragments:
// a conforming interface), linear tetrahedra of 0.1 m; metres, y up, z across.
// A user's gauge (Point 100) inside the cube, named but not embedded in it.
SetFactory("OpenCASCADE");
Box(1) = {-0.2, -0.1, 0, 0.4, 0.1, 0.3};
Box(2) = {-0.1, 0, 0.05, 0.2, 0.2, 0.2};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
e = 1e-6;
Physical Volume("slab") = Volume In BoundingBox{-0.2-e, -0.1-e, -e, 0.2+e, e, 0.3+e};
Physical Volume("block") = Volume In BoundingBox{-0.1-e, -e, 0.05-e, 0.1+e, 0.2+e, 0.25+e};
Physical Surface("interface") = Surface In BoundingBox{-0.1-e, -e, 0.05-e, 0.1+e, e, 0.25+e};
Physical Surface("slab_bottom") = Surface In BoundingBox{-0.2-e, -0.1-e, -e, 0.2+e, -0.1+e, 0.3+e};
Point(100) = {0, 0.1, 0.15};
Physical Point("gauge") = {100};
MeshSize{ PointsOf{ Volume{:}; } } = 0.1;
