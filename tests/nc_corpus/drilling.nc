%
O4001 (DRILLING CYCLES G81 G82 G83)
(Written for the machinesim corpus.)
G90 G21 G94 G54 G17
G00 X0. Y0. Z10.
G98 G81 X5. Y5. Z-2. R1. F100. (two holes 2 mm deep, back to the initial level)
X10.
G80
G99 G82 X5. Y10. Z-1.5 R0.5 P250 F80. (a spot hole with a 0.25 s dwell, back to R)
G80 G00 Z10.
G98 G83 X10. Y10. Z-3. R1. Q1.2 F60. (peck drilling 4 mm in pecks of 1.2 mm)
G80
M30
%
