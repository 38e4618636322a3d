// h_tet_slab.geo without BooleanFragments: the block and the slab meshed apart, the
// block's base (the group 'interface') sharing no node with the slab's top.
SetFactory("OpenCASCADE");
Box(1) = {-0.4, -0.1, 0, 0.8, 0.1, 0.5};
Box(2) = {-0.15, 0, 0.125, 0.3, 0.2, 0.25};
e = 1e-6;
Physical Volume("slab") = {1};
Physical Volume("block") = {2};
Physical Surface("interface") = Surface In BoundingBox{-0.15-e, -e, 0.125-e, 0.15+e, e, 0.375+e};
Physical Surface("slab_bottom") = Surface In BoundingBox{-0.4-e, -0.1-e, -e, 0.4+e, -0.1+e, 0.5+e};
MeshSize{ PointsOf{ Volume{:}; } } = 0.1;
