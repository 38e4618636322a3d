// A block meshed 2 mm above its base, separately (a general pair): the sliding-block example's
// geometry (examples/sliding_block/blocks.geo) with a shorter base. Units: m.
// base: [-0.2, 0.2] x [-0.1, 0], 10 mm facets on its top; block: [-0.1, 0.1] x [0.002, 0.102]
Point(1) = {-0.2, -0.1, 0}; Point(2) = {0.2, -0.1, 0};
Point(3) = {0.2, 0, 0}; Point(4) = {-0.2, 0, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{1, 3} = 41; Transfinite Curve{2, 4} = 6;
Transfinite Surface{1};

Point(5) = {-0.1, 0.002, 0}; Point(6) = {0.1, 0.002, 0};
Point(7) = {0.1, 0.102, 0}; Point(8) = {-0.1, 0.102, 0};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};
Transfinite Curve{5, 7} = 8; Transfinite Curve{6, 8} = 5;
Transfinite Surface{2};

Physical Surface("base") = {1};
Physical Surface("block") = {2};
Physical Curve("base_bottom") = {1};
Physical Curve("base_top") = {3};
Physical Curve("block_bottom") = {5};
Physical Curve("block_left") = {8};
Physical Point("block_corner") = {5};
