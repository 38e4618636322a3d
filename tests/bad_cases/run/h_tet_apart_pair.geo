// h_tet_apart.geo with its groups for a 3-D general pair: the block's base (slave) and the
// slab's top (master) meshed apart, rollers in z on the slab's sides and the block's back.
SetFactory("OpenCASCADE");
Box(1) = {-0.4, -0.1, 0, 0.8, 0.1, 0.5};
Box(2) = {-0.15, 0, 0.125, 0.3, 0.2, 0.25};
e = 1e-6;
Physical Volume("slab") = {1};
Physical Volume("block") = {2};
Physical Surface("block_base") = {9};
Physical Surface("slab_top") = {4};  // OCC box faces: xmin,xmax,ymin,ymax,zmin,zmax
Physical Surface("slab_bottom") = Surface In BoundingBox{-0.4-e, -0.1-e, -e, 0.4+e, -0.1+e, 0.5+e};
Physical Surface("block_left") = Surface In BoundingBox{-0.15-e, -e, 0.125-e, -0.15+e, 0.2+e, 0.375+e};
Physical Surface("slab_sides") = Surface In BoundingBox{-0.4-e, -0.1-e, -e, 0.4+e, e, e};
Physical Surface("slab_sides") += Surface In BoundingBox{-0.4-e, -0.1-e, 0.5-e, 0.4+e, e, 0.5+e};
Physical Surface("block_back") = Surface In BoundingBox{-0.15-e, -e, 0.125-e, 0.15+e, 0.2+e, 0.125+e};
MeshSize{ PointsOf{ Volume{:}; } } = 0.1;
