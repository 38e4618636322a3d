// A block resting on a base meshed apart (a general pair), the base's top in three
// facet groups: top_l, top_m (under the block's middle) and top_r. Units: m.
h = 0.02;
Point(1) = {-0.2, -0.1, 0, h}; Point(2) = {0.6, -0.1, 0, h};
Point(3) = {0.6, 0, 0, h}; Point(4) = {-0.2, 0, 0, h};
Point(21) = {0.05, 0, 0, h}; Point(22) = {-0.05, 0, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 21}; Line(31) = {21, 22};
Line(32) = {22, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 31, 32, 4}; Plane Surface(1) = {1};
Point(5) = {-0.1, 0, 0, h}; Point(6) = {0.1, 0, 0, h};
Point(7) = {0.1, 0.1, 0, h}; Point(8) = {-0.1, 0.1, 0, h};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};
Physical Surface("base") = {1};
Physical Surface("block") = {2};
Physical Curve("base_bottom") = {1};
Physical Curve("top_r") = {3};
Physical Curve("top_m") = {31};
Physical Curve("top_l") = {32};
Physical Curve("block_bottom") = {5};
