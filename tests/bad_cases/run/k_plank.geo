// A long plank (fine, 10 mm) on a short pedestal (coarse, 80 mm: ratio 8), meshed 0.1 mm apart
// (bad run k1: its frictional static state stalls above [initial] tolerance).
hp = 0.01; hb = 0.08; gap = 1e-4;
Point(1) = {-0.1, -0.3, 0, hb}; Point(2) = {0.1, -0.3, 0, hb}; Point(3) = {0.1, 0, 0, hb}; Point(4) = {-0.1, 0, 0, hb};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1:4}; Plane Surface(1) = {1};
Point(5) = {-0.3, gap, 0, hp}; Point(6) = {0.3, gap, 0, hp}; Point(7) = {0.3, gap + 0.05, 0, hp}; Point(8) = {-0.3, gap + 0.05, 0, hp};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
Curve Loop(2) = {5:8}; Plane Surface(2) = {2};
Physical Surface("pedestal") = {1};
Physical Surface("plank") = {2};
Physical Curve("ped_bottom") = {1};
Physical Curve("ped_top") = {3};
Physical Curve("ped_sides") = {2, 4};
Physical Curve("plank_bottom") = {5};
Physical Curve("plank_left") = {8};
Physical Point("plank_corner") = {5};
