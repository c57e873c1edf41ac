// A block W x H held above a slope of angle A (descending to the right):
// its bottom ("bottom", the contact surface) parallel to the slope, a gap
// D above it. The slope itself is not meshed: it is the rigid foundation
// of case.toml, the line through the origin with the normal
// (sin A, cos A).
//
//   gmsh -2 -order 1 block.geo -o block.msh
DefineConstant[
  W = {1.0, Name "Parameters/Width W"},
  H = {0.5, Name "Parameters/Height H"},
  D = {0.05, Name "Parameters/Gap D above the slope"},
  A = {20.0, Name "Parameters/Slope angle A (degrees)"},
  nx = {8, Name "Parameters/Divisions along the slope"},
  ny = {4, Name "Parameters/Divisions across it"}
];
a = A * Pi / 180;
tx = Cos(a); ty = -Sin(a);  // along the slope, downhill
nx_ = Sin(a); ny_ = Cos(a); // its normal, towards the block
Point(1) = {D * nx_, D * ny_, 0};
Point(2) = {D * nx_ + W * tx, D * ny_ + W * ty, 0};
Point(3) = {(D + H) * nx_ + W * tx, (D + H) * ny_ + W * ty, 0};
Point(4) = {(D + H) * nx_, (D + H) * ny_, 0};
Line(1) = {1, 2};  // bottom: lands on the slope
Line(2) = {2, 3};  // downhill end
Line(3) = {3, 4};  // top
Line(4) = {4, 1};  // uphill end
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 3} = nx + 1;
Transfinite Curve{2, 4} = ny + 1;
Transfinite Surface{1} = {1, 2, 3, 4};
Recombine Surface{1};

Physical Curve("bottom", 1) = {1};
Physical Curve("downhill", 2) = {2};
Physical Curve("top", 3) = {3};
Physical Curve("uphill", 4) = {4};
Physical Surface("block", 10) = {1};
