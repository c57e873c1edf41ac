// A wedge whose rough face is inclined: the contact line runs from (0, 0)
// up to (L, D), at atan(D / L) = 14.04 degrees for L = 4, D = 1. The top
// y = H is held by rollers, the left end in x, the right end is loaded.
//
//   gmsh -2 -order 2 wedge.geo -o wedge.msh
DefineConstant[
  L = {4.0, Name "Parameters/Length L"},
  D = {1.0, Name "Parameters/Rise of the contact line D"},
  H = {2.0, Name "Parameters/Height of the top H"},
  nx = {16, Name "Parameters/Divisions along x"},
  ny = {4, Name "Parameters/Divisions across"}
];
Point(1) = {0, 0, 0};
Point(2) = {L, D, 0};
Point(3) = {L, H, 0};
Point(4) = {0, H, 0};
Line(1) = {1, 2};  // inclined contact line
Line(2) = {2, 3};  // right end, x = L
Line(3) = {3, 4};  // top, y = H
Line(4) = {4, 1};  // left end, x = 0
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 3} = nx + 1;
Transfinite Curve{2, 4} = ny + 1;
Transfinite Surface{1} = {1, 2, 3, 4};
Recombine Surface{1};
// quad9 (Gmsh type 10), not the 8-node serendipity quad.
Mesh.SecondOrderIncomplete = 0;

Physical Curve("contact", 1) = {1};
Physical Curve("load", 2) = {2};
Physical Curve("support", 3) = {3};
Physical Curve("left", 4) = {4};
Physical Surface("body", 10) = {1};
