// examples/goda_apart/goda_apart.geo coarsened (20 mm caisson, 40 mm mound, 25 mm crest)
// and meshed in quadrilaterals: Frontal-Delaunay for quads (8), recombined, subdivided.
// Its frictionless static state moves the caisson sideways about 10 times its sinking.
// Units: m; the groups of meshes/goda.py with conforming = false.
Mesh.Algorithm = 8;
Mesh.SubdivisionAlgorithm = 1;
hc = 0.02;   // caisson
hm = 0.04;   // mound
hi = 0.025;  // mound crest under the caisson
// mound: base 1.16 m (crest 0.40 m, height 0.19 m, slopes 1:2)
Point(1) = {-0.58, 0, 0, hm}; Point(2) = {0.58, 0, 0, hm};
Point(3) = {0.20, 0.19, 0, hm}; Point(4) = {-0.20, 0.19, 0, hm};
Point(5) = {0.1025, 0.19, 0, hi}; Point(6) = {-0.1025, 0.19, 0, hi};
Line(1) = {1, 2}; Line(2) = {2, 3};
Line(3) = {3, 5}; Line(4) = {5, 6}; Line(5) = {6, 4};   // the crest, three pieces
Line(6) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6}; Plane Surface(1) = {1};
// caisson: [-0.1025, 0.1025] x [0.19, 0.392]; front face x = -0.1025 (struck in +x)
Point(11) = {-0.1025, 0.19, 0, hc}; Point(12) = {0.1025, 0.19, 0, hc};
Point(13) = {0.1025, 0.392, 0, hc}; Point(14) = {-0.1025, 0.392, 0, hc};
Point(15) = {-0.1025, 0.351, 0, hc};   // gauge_top, 41 mm below the top
Point(16) = {-0.1025, 0.363, 0, hc};   // impact patch 0.353-0.363 (bolt 168 mm)
Point(17) = {-0.1025, 0.353, 0, hc};
Point(18) = {-0.1025, 0.231, 0, hc};   // gauge_bottom, 41 mm above the base
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14};
Line(14) = {14, 16}; Line(15) = {16, 17}; Line(16) = {17, 15}; Line(17) = {15, 18};
Line(18) = {18, 11};
Curve Loop(2) = {11, 12, 13, 14, 15, 16, 17, 18}; Plane Surface(2) = {2};

Physical Surface("mound") = {1};
Physical Surface("caisson") = {2};
Physical Curve("base") = {1};
Physical Curve("mound_surface") = {2, 6};
Physical Curve("mound_crest") = {3, 4, 5};
Physical Curve("caisson_base") = {11};
Physical Curve("caisson_rear") = {12};
Physical Curve("caisson_top") = {13};
Physical Curve("impact") = {15};
Physical Curve("caisson_front") = {14, 16, 17, 18};
Physical Point("gauge_top") = {15};
Physical Point("gauge_bottom") = {18};
Physical Point("corner_front") = {11};
Physical Point("corner_rear") = {12};
Recombine Surface{1, 2};
