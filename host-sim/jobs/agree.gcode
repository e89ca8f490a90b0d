(The same job offline, over the pty and under QEMU: each must end on the)
(same step. Tool, spindle and coolant words share lines, and M2 ends the)
(program mid-file: a streamed job goes on after it, in GRBL's way.)
G21 G90 G94
T2 M3 S1000 M8
G1 X10 Y5 F3000
G2 X20 Y5 I5 J0 F2000
M5 M9 T1
G1 X12.5 Y-2 Z1 F1500
G4 P0.1
M2
G91 G0 X3 Y4 Z-1
G90 G1 X5.0125 F1000
G18 G3 X5.0125 Z0.5 I0 K0.25 F800
