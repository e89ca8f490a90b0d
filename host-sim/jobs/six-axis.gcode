( six axes: every axis moves, alone and together; run on machines/six-axis.toml )
G21 G90 G94
G0 X10 Y5 Z-2
G1 A90 F3600
G1 B-45 F3600
G1 C30 F3600
G1 X20 Y10 Z-1 A180 B45 C-30 F1200
G0 X12.5 Y-7.25 Z-3 A270 B-90 C120
M2
