(Reversing lines and an arc: every move reverses X or Y or both.)
(host-sim/machines/backlash.toml: 0.1 mm of slack on X and Y.)
G21 G90 G17 G94
G1 X10 Y0 F1200
G1 X2 Y4
G1 X10 Y8
G1 X0 Y8
G2 X0 Y0 I0 J-4
G1 X6 Y3
G3 X2 Y3 I-2 J0
G1 X0 Y0
