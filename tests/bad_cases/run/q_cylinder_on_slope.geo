// A cylinder (R = 5 cm) on a slope tilted by 30 degrees, meshed apart; second order
th = 30*Pi/180; R = 0.05; hc = 0.012; hs = 0.025;
Point(1) = {0, -0.1, 0, hs}; Point(2) = {1, -0.1, 0, hs}; Point(3) = {1, 0, 0, hs}; Point(4) = {0, 0, 0, hs};
Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,4}; Line(4) = {4,1};
Curve Loop(1) = {1,2,3,4}; Plane Surface(1) = {1};
xc = 0.6; 
Point(10) = {xc, R, 0, hc}; Point(11) = {xc, 0, 0, hc}; Point(12) = {xc+R, R, 0, hc}; Point(13) = {xc, 2*R, 0, hc}; Point(14) = {xc-R, R, 0, hc};
Circle(11) = {11,10,12}; Circle(12) = {12,10,13}; Circle(13) = {13,10,14}; Circle(14) = {14,10,11};
Curve Loop(2) = {11,12,13,14}; Plane Surface(2) = {2};
Point{10} In Surface{2};
Rotate {{0,0,1},{0,0,0}, th} { Surface{1,2}; }
Physical Surface("slope") = {1};
Physical Surface("cylinder") = {2};
Physical Curve("slope_top") = {3};
Physical Curve("slope_bottom") = {1};
Physical Curve("rim") = {11,12,13,14};
Physical Point("centre") = {10};
Mesh.ElementOrder = 2;
