// A block (0.2 x 0.1 m) on a base (0.4 x 0.1 m) sharing their interface (conforming),
// 20 mm elements.
h = 0.02;
Point(1) = {-0.2, -0.1, 0, h}; Point(2) = {0.2, -0.1, 0, h}; Point(3) = {0.2, 0, 0, h};
Point(4) = {0.1, 0, 0, h}; Point(5) = {-0.1, 0, 0, h}; Point(6) = {-0.2, 0, 0, h};
Point(7) = {0.1, 0.1, 0, h}; Point(8) = {-0.1, 0.1, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6};
Line(6) = {6, 1}; Line(7) = {4, 7}; Line(8) = {7, 8}; Line(9) = {8, 5};
Curve Loop(1) = {1, 2, 3, 4, 5, 6}; Plane Surface(1) = {1};
Curve Loop(2) = {-4, 7, 8, 9}; Plane Surface(2) = {2};
Physical Surface("base") = {1}; Physical Surface("block") = {2};
Physical Curve("base_bottom") = {1}; Physical Curve("interface") = {4};
Physical Curve("block_left") = {9};
