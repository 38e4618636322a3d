// m_slab3d.geo's cube on its slab, with a gauge at the cube's front base edge embedded
// in the interface surface (whose boundary it lies on): gmsh's 3D Delaunay logs
// "No elements in volume 1 2" and returns without a tetrahedron.
SetFactory("OpenCASCADE");
Box(1) = {-0.2, -0.1, 0, 0.4, 0.1, 0.3};
Box(2) = {-0.1, 0, 0.05, 0.2, 0.2, 0.2};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
e = 1e-6;
Physical Volume("slab") = Volume In BoundingBox{-0.2-e, -0.1-e, -e, 0.2+e, e, 0.3+e};
Physical Volume("block") = Volume In BoundingBox{-0.1-e, -e, 0.05-e, 0.1+e, 0.2+e, 0.25+e};
bottom() = Surface In BoundingBox{-0.1-e, -e, 0.05-e, 0.1+e, e, 0.25+e};
Physical Surface("interface") = {bottom()};
Physical Surface("slab_bottom") = Surface In BoundingBox{-0.2-e, -0.1-e, -e, 0.2+e, -0.1+e, 0.3+e};
Point(100) = {-0.1, 0, 0.15};
Point{100} In Surface{bottom(0)};
Physical Point("corner_front") = {100};
MeshSize{ PointsOf{ Volume{:}; } } = 0.1;
Mesh.Algorithm3D = 1;
