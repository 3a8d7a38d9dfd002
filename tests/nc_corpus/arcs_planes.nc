%
O2001 (ARCS IN THE THREE PLANES, CENTRE AND RADIUS FORMS, HELICES)
(Written for the machinesim corpus. Every arc is centred on the origin.)
G90 G21 G94 G54
G17
G00 X10. Y0. Z1.
G01 Z0. F100.
G03 X0. Y10. I-10. J0. (XY quarter, counter-clockwise, centre form)
G03 X-10. Y0. R10. (XY quarter, radius form: the arc up to 180 deg)
G02 X0. Y-10. R-10. (XY three quarters, clockwise: R < 0 is the arc over 180 deg)
G03 X0. Y-10. Z-1. I0. J10. (XY full circle with Z: a helix of pitch 1 mm)
G00 Z1.
G18
G00 X5. Y0. Z0.
G02 X0. Z5. I-5. K0. (ZX quarter, clockwise seen from +Y)
G19
G00 X0. Y5. Z0.
G03 X2. Y0. Z5. J-5. K0. (YZ quarter, counter-clockwise seen from +X, helical in X)
M30
%
