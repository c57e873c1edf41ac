// A block W x H resting on a rigid, rough base (the bottom face, "base"),
// pushed on its left face ("push") towards a rigid wall that holds its right
// face ("wall"); the top is free.
//
//   gmsh -2 -order 1 block.geo -o block.msh
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
Line(1) = {1, 2};  // bottom: on the base
Line(2) = {2, 3};  // right: against the wall
Line(3) = {3, 4};  // top: free
Line(4) = {4, 1};  // left: pushed
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 3} = nx + 1;
Transfinite Curve{2, 4} = ny + 1;
Transfinite Surface{1} = {1, 2, 3, 4};
Recombine Surface{1};
Mesh.SecondOrderIncomplete = 0;

Physical Curve("base", 1) = {1};
Physical Curve("wall", 2) = {2};
Physical Curve("top", 3) = {3};
Physical Curve("push", 4) = {4};
Physical Surface("block", 10) = {1};
