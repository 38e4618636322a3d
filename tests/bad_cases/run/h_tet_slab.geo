// A user's own 3D mesh (not breakwater's builders): a 0.3 x 0.2 x 0.25 m block on a
// 0.8 x 0.1 x 0.5 m slab, sharing the block's base (BooleanFragments: a conforming
// interface), linear tetrahedra of 0.1 m by gmsh's default 3D algorithm; metres, y up,
// z across. The slab's faces z = 0 and z = 0.5 are one group (side walls: rollers).
SetFactory("OpenCASCADE");
Box(1) = {-0.4, -0.1, 0, 0.8, 0.1, 0.5};
Box(2) = {-0.15, 0, 0.125, 0.3, 0.2, 0.25};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
e = 1e-6;
Physical Volume("slab") = Volume In BoundingBox{-0.4-e, -0.1-e, -e, 0.4+e, e, 0.5+e};
Physical Volume("block") = Volume In BoundingBox{-0.15-e, -e, 0.125-e, 0.15+e, 0.2+e, 0.375+e};
Physical Surface("interface") = Surface In BoundingBox{-0.15-e, -e, 0.125-e, 0.15+e, e, 0.375+e};
Physical Surface("slab_bottom") = Surface In BoundingBox{-0.4-e, -0.1-e, -e, 0.4+e, -0.1+e, 0.5+e};
Physical Surface("block_left") = Surface In BoundingBox{-0.15-e, -e, 0.125-e, -0.15+e, 0.2+e, 0.375+e};
Physical Surface("slab_sides") = Surface In BoundingBox{-0.4-e, -0.1-e, -e, 0.4+e, e, e};
Physical Surface("slab_sides") += Surface In BoundingBox{-0.4-e, -0.1-e, 0.5-e, 0.4+e, e, 0.5+e};
Physical Point("top_corner") = Point In BoundingBox{-0.15-e, 0.2-e, 0.125-e, -0.15+e, 0.2+e, 0.125+e};
MeshSize{ PointsOf{ Volume{:}; } } = 0.1;
