// The paper's slab (Martins & Oden 1983, §4.3; shared/BENCHMARK.md):
// [0, L] x [0, H] = [0, 8] x [0, 1], meshed with nx x ny quadrilaterals.
//
//   gmsh -2 -order 2 slab.geo -o slab-q2-8x2.msh                    (the paper's 85-node mesh)
//   gmsh -2 -order 1 slab.geo -setnumber nx 16 -setnumber ny 4 -o slab-q1-16x4.msh
//
// The element order is not a parameter here: pass -order 1|2 on the command
// line (or gmsh.model.mesh.setOrder / Mesh.ElementOrder from the API).
// structured = 0 gives an unstructured all-quad mesh of the same slab
// (nx, ny then only set the target element size L/nx).
DefineConstant[
  L = {8.0, Name "Parameters/Length L"},
  H = {1.0, Name "Parameters/Height H"},
  nx = {8, Name "Parameters/Divisions along x"},
  ny = {2, Name "Parameters/Divisions along y"},
  structured = {1, Choices{0, 1}, Name "Parameters/Structured (transfinite)"}
];

lc = L / nx;
Point(1) = {0, 0, 0, lc};
Point(2) = {L, 0, 0, lc};
Point(3) = {L, H, 0, lc};
Point(4) = {0, H, 0, lc};
Line(1) = {1, 2};  // bottom, y = 0
Line(2) = {2, 3};  // right end, x = L
Line(3) = {3, 4};  // top, y = H
Line(4) = {4, 1};  // left end, x = 0
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

If (structured)
  Transfinite Curve{1, 3} = nx + 1;
  Transfinite Curve{2, 4} = ny + 1;
  Transfinite Surface{1} = {1, 2, 3, 4};
Else
  // Frontal-Delaunay triangles, then Blossom full-quad recombination, so
  // that every cell is a quadrilateral (no triangles left over). (Frontal-
  // Delaunay for quads, Mesh.Algorithm = 8, would give the regular grid on
  // this rectangle: nodes of 3 and 5 cells are what make it unstructured.)
  Mesh.Algorithm = 6;
  Mesh.RecombinationAlgorithm = 3;
EndIf
Recombine Surface{1};

// quad9 (Gmsh type 10), not the 8-node serendipity quad.
Mesh.SecondOrderIncomplete = 0;

Physical Curve("contact", 1) = {1};
Physical Curve("load", 2) = {2};
Physical Curve("support", 3) = {3};
Physical Curve("left", 4) = {4};
Physical Surface("body", 10) = {1};
