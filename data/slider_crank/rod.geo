// Connecting rod of the slider-crank (Tromme et al., section 5), reconstructed.
// The paper's Fig. 3 (dimensions) is not available: this outline is a plausible
// diesel connecting rod whose free dimensions were calibrated so that the initial
// design matches the paper's mass (295.664 g) and maximum elongation (13.508 um);
// see README.md and calibrate.py. Units: mm. Rod axis along x; small end (gudgeon pin)
// bore centre at (0, 0), big end (crank pin) bore centre at (L, 0): with this choice the
// paper's Table 3 holes at their optimum lie in the shank (with the big end at the origin the
// holes 2 and 3 would cut the big-end boss).
// Structured (transfinite) quadrilateral mesh, as in the paper.
//
// Regenerate:  gmsh -2 rod.geo -format msh41 -o rod.msh
// Parameters can be overridden: gmsh -setnumber lc 3 -2 rod.geo -o rod_coarse.msh

If (!Exists(L))   L = 135.6;  EndIf   // centre distance (paper: hole centre 67.8 mm = L/2)
If (!Exists(Rbi)) Rbi = 22.0; EndIf   // big-end bore radius (crank pin)
If (!Exists(Rbo)) Rbo = 29.1768; EndIf   // big-end boss outer radius
If (!Exists(Rsi)) Rsi = 11.0; EndIf   // small-end bore radius (gudgeon pin)
If (!Exists(Rso)) Rso = 18.0; EndIf   // small-end boss outer radius
If (!Exists(hb)) hb = 13.3182;  EndIf   // shank half-width where it meets the big end
If (!Exists(hs)) hs = 8.8788;   EndIf   // shank half-width where it meets the small end
If (!Exists(lc))  lc = 1.25;  EndIf   // target element size

alpha = Asin(hb / Rbo);
beta  = Asin(hs / Rso);

// ---- small end (centre 1)
Point(1) = {0, 0, 0};
Point(2) = {Rsi * Cos(-beta), Rsi * Sin(-beta), 0};
Point(3) = {Rsi * Cos(beta),  Rsi * Sin(beta),  0};
Point(4) = {-Rsi, 0, 0};
Point(5) = {Rso * Cos(-beta), Rso * Sin(-beta), 0};
Point(6) = {Rso * Cos(beta),  Rso * Sin(beta),  0};
Point(7) = {-Rso, 0, 0};
Circle(1) = {2, 1, 3};  Circle(2) = {3, 1, 4};  Circle(3) = {4, 1, 2};   // bore
Circle(4) = {5, 1, 6};  Circle(5) = {6, 1, 7};  Circle(6) = {7, 1, 5};   // boss
Line(7) = {2, 5};  Line(8) = {3, 6};  Line(9) = {4, 7};

// ---- big end (centre 11)
Point(11) = {L, 0, 0};
Point(12) = {L + Rbi * Cos(Pi - alpha), Rbi * Sin(Pi - alpha), 0};
Point(13) = {L + Rbi * Cos(Pi + alpha), Rbi * Sin(Pi + alpha), 0};
Point(14) = {L + Rbi, 0, 0};
Point(15) = {L + Rbo * Cos(Pi - alpha), Rbo * Sin(Pi - alpha), 0};
Point(16) = {L + Rbo * Cos(Pi + alpha), Rbo * Sin(Pi + alpha), 0};
Point(17) = {L + Rbo, 0, 0};
Circle(11) = {12, 11, 13};  Circle(12) = {13, 11, 14};  Circle(13) = {14, 11, 12};  // bore
Circle(14) = {15, 11, 16};  Circle(15) = {16, 11, 17};  Circle(16) = {17, 11, 15};  // boss
Line(17) = {12, 15};  Line(18) = {13, 16};  Line(19) = {14, 17};

// ---- shank: straight tapered edges from boss to boss
Line(21) = {6, 15};   // top
Line(22) = {5, 16};   // bottom

// ---- element counts (opposite sides of every patch match)
nw  = Ceil(2 * hb / lc);                               // across the shank
nL  = Ceil((L - Rso * Cos(beta) - Rbo * Cos(alpha)) / lc);
nrb = Ceil((Rbo - Rbi) / lc);
nrs = Ceil((Rso - Rsi) / lc);
nb2 = Ceil(0.5 * (Rbi + Rbo) * (Pi - alpha) / lc);
ns2 = Ceil(0.5 * (Rsi + Rso) * (Pi - beta) / lc);

Transfinite Curve {1, 4, 11, 14} = nw + 1;
Transfinite Curve {2, 3, 5, 6} = ns2 + 1;
Transfinite Curve {12, 13, 15, 16} = nb2 + 1;
Transfinite Curve {7, 8, 9} = nrs + 1;
Transfinite Curve {17, 18, 19} = nrb + 1;
Transfinite Curve {21, 22} = nL + 1;

Curve Loop(1) = {7, 4, -8, -1};     Plane Surface(1) = {1};
Curve Loop(2) = {8, 5, -9, -2};     Plane Surface(2) = {2};
Curve Loop(3) = {9, 6, -7, -3};     Plane Surface(3) = {3};
Curve Loop(4) = {17, 14, -18, -11}; Plane Surface(4) = {4};
Curve Loop(5) = {18, 15, -19, -12}; Plane Surface(5) = {5};
Curve Loop(6) = {19, 16, -17, -13}; Plane Surface(6) = {6};
Curve Loop(7) = {22, -14, -21, -4}; Plane Surface(7) = {7};

Transfinite Surface {1} = {2, 5, 6, 3};
Transfinite Surface {2} = {3, 6, 7, 4};
Transfinite Surface {3} = {4, 7, 5, 2};
Transfinite Surface {4} = {12, 15, 16, 13};
Transfinite Surface {5} = {13, 16, 17, 14};
Transfinite Surface {6} = {14, 17, 15, 12};
Transfinite Surface {7} = {5, 16, 15, 6};
Recombine Surface {1, 2, 3, 4, 5, 6, 7};

Physical Curve("bore_small") = {1, 2, 3};
Physical Curve("bore_big") = {11, 12, 13};
Physical Surface("rod") = {1, 2, 3, 4, 5, 6, 7};

Mesh.MshFileVersion = 4.1;
