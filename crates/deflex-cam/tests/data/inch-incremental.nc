%
O0042
(inch program, incremental moves, a YZ-plane arc, dwell and home return: written for the tests)
N1 G20 G17 G40 G90
N2 G0 X1.0 Y1.0 Z0.2
N3 G1 Z0.0 F20.
N4 G91 G1 X0.5
N5 Y-0.25
N6 G4 P500
/N7 G90 G19 G2 Y1.25 Z0.5 J0.5 K0.
N8 G17 G90 G0 Z1.0
N9 G91 G28 Z0.
N10 M30
N11 G0 X99
%
