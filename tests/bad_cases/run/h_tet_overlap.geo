// A user's block meshed 2 mm into a slab (overlapping), apart (no BooleanFragments): a
// 0.3 x 0.2 x 0.25 m block, its base at y = -2 mm, in a 0.8 x 0.1 x 0.5 m slab, linear
// tetrahedra of 0.1 m; the faces by their OpenCASCADE tags (Box: x-, x+, y-, y+, z-, z+).
SetFactory("OpenCASCADE");
Box(1) = {-0.4, -0.1, 0, 0.8, 0.1, 0.5};
Box(2) = {-0.15, -0.002, 0.125, 0.3, 0.2, 0.25};
Physical Volume("slab") = {1};
Physical Volume("block") = {2};
Physical Surface("slab_bottom") = {3};
Physical Surface("slab_top") = {4};
Physical Surface("block_left") = {7};
Physical Surface("block_bottom") = {9};
Physical Surface("block_top") = {10};
Physical Surface("block_back") = {11};
MeshSize{ PointsOf{ Volume{:}; } } = 0.1;
