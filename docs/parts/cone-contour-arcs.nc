%
O2301 (CONE 40 DIA 45 DEG 6 DEEP - CONTOUR ARCS)
(deflex example part, written for the tests and the README walk-through; MIT licence.)
(Post: Fanuc-style 3-axis. Tool: 10 mm ball, TCP = ball centre. Stock: 0.5 mm AA3003.)
(A 45 deg cone, 40 mm TCP-path diameter at the top, 6 mm deep, in 12 contour levels of)
(0.5 mm: each level a full circle - G3 with I J - stepped down and in by a short G1; a)
(tangential lead-in arc in the ZX plane - G18 G2 with I K - and a retract at the end.)
(Part frame G54: origin on the cone axis, Z0 where the ball touches the flat sheet.)
N10 G17 G21 G40 G49 G80 G90 G94
N20 G54
N30 T1 M6 (10 MM BALL FORMING TOOL)
N40 M5
N50 G0 X25. Y0.
N60 G0 Z5.
N70 G18 G2 X20. Z0. I0. K-5. F300.
N80 G17
N90 F600.
N100 G1 X19.5 Z-0.5
N110 G3 X19.5 Y0. I-19.5 J0.
N120 G1 X19.0 Z-1.0
N130 G3 X19.0 Y0. I-19.0 J0.
N140 G1 X18.5 Z-1.5
N150 G3 X18.5 Y0. I-18.5 J0.
N160 G1 X18.0 Z-2.0
N170 G3 X18.0 Y0. I-18.0 J0.
N180 G1 X17.5 Z-2.5
N190 G3 X17.5 Y0. I-17.5 J0.
N200 G1 X17.0 Z-3.0
N210 G3 X17.0 Y0. I-17.0 J0.
N220 G1 X16.5 Z-3.5
N230 G3 X16.5 Y0. I-16.5 J0.
N240 G1 X16.0 Z-4.0
N250 G3 X16.0 Y0. I-16.0 J0.
N260 G1 X15.5 Z-4.5
N270 G3 X15.5 Y0. I-15.5 J0.
N280 G1 X15.0 Z-5.0
N290 G3 X15.0 Y0. I-15.0 J0.
N300 G1 X14.5 Z-5.5
N310 G3 X14.5 Y0. I-14.5 J0.
N320 G1 X14.0 Z-6.0
N330 G3 X14.0 Y0. I-14.0 J0.
N340 G0 Z5.
N350 M30
%
