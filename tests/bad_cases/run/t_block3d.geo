// One elastic block, 0.1 x 0.1 x 0.1 m, linear tetrahedra of 0.05 m: the tiny 3D mesh of
// the t* bad runs (loads). The faces by their OpenCASCADE tags (Box: x-, x+, y-, y+, z-,
// z+); "ends": the two faces normal to z. Units: m.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.1, 0.1, 0.1};
Physical Volume("block") = {1};
Physical Surface("bottom") = {3};
Physical Surface("ends") = {5, 6};
MeshSize{ PointsOf{ Volume{:}; } } = 0.05;
