// A block on a slab drawn in x-y and extruded 0.2 m across (z) in layers, its
// triangles not recombined: prisms (6-node wedges).
h = 0.05;
Point(1) = {-0.2, -0.1, 0, h}; Point(2) = {0.2, -0.1, 0, h}; Point(3) = {0.2, 0, 0, h};
Point(4) = {0.1, 0, 0, h}; Point(5) = {-0.1, 0, 0, h}; Point(6) = {-0.2, 0, 0, h};
Point(7) = {0.1, 0.1, 0, h}; Point(8) = {-0.1, 0.1, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6};
Line(6) = {6, 1}; Line(7) = {4, 7}; Line(8) = {7, 8}; Line(9) = {8, 5};
Curve Loop(1) = {1, 2, 3, 4, 5, 6}; Plane Surface(1) = {1};
Curve Loop(2) = {-4, 7, 8, 9}; Plane Surface(2) = {2};
out[] = Extrude {0, 0, 0.2} { Surface{1, 2}; Layers{2}; Recombine; };
Physical Volume("slab") = {out[1]};
Physical Volume("block") = {out[9]};
Physical Surface("interface") = {out[5]};
Physical Surface("slab_bottom") = {out[2]};
