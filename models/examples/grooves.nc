%
O1 (four straight V grooves across a 10 x 10 mm block, 20 um deep; mm, deg)
G90 G21 G94 G54
G00 X-1. Y2. Z0.1
Z-0.02
G01 X11. F100.
G00 Z0.1
Y4.
Z-0.02
G01 X-1.
G00 Z0.1
Y6.
Z-0.02
G01 X11.
G00 Z0.1
Y8.
Z-0.02
G01 X-1.
G00 Z0.1
M30
%
