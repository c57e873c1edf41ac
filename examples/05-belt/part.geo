// A pad W x H resting on a conveyor belt (its bottom, "belt", the contact
// surface), clamped at its top ("top"); its ends ("left", "right") free.
//
//   gmsh -2 -order 1 part.geo -o part.msh
DefineConstant[
  W = {2.0, Name "Parameters/Width W"},
  H = {1.0, Name "Parameters/Height H"},
  nx = {16, Name "Parameters/Divisions along x"},
  ny = {8, Name "Parameters/Divisions along y"}
];
Point(1) = {0, 0, 0};
Point(2) = {W, 0, 0};
Point(3) = {W, H, 0};
Point(4) = {0, H, 0};
Line(1) = {1, 2};  // bottom: on the belt
Line(2) = {2, 3};  // right: free
Line(3) = {3, 4};  // top: clamped
Line(4) = {4, 1};  // left: free
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 3} = nx + 1;
Transfinite Curve{2, 4} = ny + 1;
Transfinite Surface{1} = {1, 2, 3, 4};
Recombine Surface{1};

Physical Curve("belt", 1) = {1};
Physical Curve("right", 2) = {2};
Physical Curve("top", 3) = {3};
Physical Curve("left", 4) = {4};
Physical Surface("part", 10) = {1};
