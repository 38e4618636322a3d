// A user's block overhanging the end of its slab by a third of its base (BooleanFragments
// splits the base into the shared part and the overhang), the interface group taken by a
// bounding box around the whole base: the overhang's facets border the block alone.
SetFactory("OpenCASCADE");
Box(1) = {-0.4, -0.1, 0, 0.8, 0.1, 0.5};
Box(2) = {0.3, 0, 0.125, 0.3, 0.2, 0.25};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
e = 1e-6;
Physical Volume("slab") = Volume In BoundingBox{-0.4-e, -0.1-e, -e, 0.4+e, e, 0.5+e};
Physical Volume("block") = Volume In BoundingBox{0.3-e, -e, 0.125-e, 0.6+e, 0.2+e, 0.375+e};
Physical Surface("interface") = Surface In BoundingBox{0.3-e, -e, 0.125-e, 0.6+e, e, 0.375+e};
Physical Surface("slab_bottom") = Surface In BoundingBox{-0.4-e, -0.1-e, -e, 0.4+e, -0.1+e, 0.5+e};
MeshSize{ PointsOf{ Volume{:}; } } = 0.1;
