// A plate with a circular hole, meshed with unstructured quadrilaterals:
// [0, L] x [0, H] = [0, 4] x [0, 2] minus the disc of radius r centred at
// (xc, yc) = (2, 1). Element size lc everywhere (lc_hole on the circle).
//
//   gmsh -2 -order 1 hole.geo -o hole-q1.msh
//   gmsh -2 -order 2 hole.geo -o hole-q2.msh
//
// The element order is passed by -order 1|2 (or setOrder from the API).
// Every cell is a quadrilateral: Frontal-Delaunay for quads (Mesh.Algorithm
// = 8) followed by the Blossom full-quad recombination (Mesh.Recombination
// Algorithm = 3), which leaves no triangles.
DefineConstant[
  L = {4.0, Name "Parameters/Length L"},
  H = {2.0, Name "Parameters/Height H"},
  xc = {2.0, Name "Parameters/Hole centre x"},
  yc = {1.0, Name "Parameters/Hole centre y"},
  r = {0.5, Name "Parameters/Hole radius"},
  lc = {0.25, Name "Parameters/Element size"},
  lc_hole = {0.125, Name "Parameters/Element size on the hole"}
];

Point(1) = {0, 0, 0, lc};
Point(2) = {L, 0, 0, lc};
Point(3) = {L, H, 0, lc};
Point(4) = {0, H, 0, lc};
Line(1) = {1, 2};  // bottom, y = 0
Line(2) = {2, 3};  // right end, x = L
Line(3) = {3, 4};  // top, y = H
Line(4) = {4, 1};  // left end, x = 0

Point(5) = {xc, yc, 0, lc_hole};       // centre (not meshed)
Point(6) = {xc + r, yc, 0, lc_hole};
Point(7) = {xc, yc + r, 0, lc_hole};
Point(8) = {xc - r, yc, 0, lc_hole};
Point(9) = {xc, yc - r, 0, lc_hole};
Circle(5) = {6, 5, 7};
Circle(6) = {7, 5, 8};
Circle(7) = {8, 5, 9};
Circle(8) = {9, 5, 6};

Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(1) = {1, 2};

Mesh.Algorithm = 8;
Mesh.RecombinationAlgorithm = 3;
Recombine Surface{1};

// quad9 (Gmsh type 10), not the 8-node serendipity quad.
Mesh.SecondOrderIncomplete = 0;

Physical Curve("contact", 1) = {1};
Physical Curve("load", 2) = {2};
Physical Curve("support", 3) = {3};
Physical Curve("left", 4) = {4};
Physical Curve("hole", 5) = {5, 6, 7, 8};
Physical Surface("body", 10) = {1};
