( burin demo: an engraved medallion                                        )
( The job `cargo xtask sim` runs when given no file. It shows most of what )
( the controller understands: rapids and feeds, G2/G3 arcs, a full circle, )
( a multi-turn helix, G5 cubic splines, a work offset, parameters,         )
( spindle and coolant M-codes, a dwell, and comments.                      )
(                                                                          )
( Made for the default machine, host-sim/machines/default.toml: it homes   )
( towards +X +Y +Z, so its envelope is X,Y in [-300, 0] and Z in [-100, 0]. )
( G10 L2 puts work zero at machine X-250 Y-250 Z-50: the 200 x 200 mm job  )
( sits well inside the envelope and Z0 is the top of the stock.            )

G21 G90 G17 G94         (millimetres, absolute, XY plane, feed per minute)
G10 L2 P1 X-250 Y-250 Z-50 (G54 origin)
G54
#1 = 15                 (frame corner radius)
#2 = 1.0                (engraving depth)
S12000 M3               (spindle on, clockwise)
M8                      (flood coolant)
G4 P1                   (let the spindle reach speed)
G0 Z5

(--- 1. a rounded frame: lines and G3 corner arcs, I/J centre format ---)
G0 X[10 + #1] Y10
G1 Z-#2 F300            (plunge)
G1 X[190 - #1] F1800
G3 X190 Y[10 + #1] I0 J#1
G1 Y[190 - #1]
G3 X[190 - #1] Y190 I-#1 J0
G1 X[10 + #1]
G3 X10 Y[190 - #1] I0 J-#1
G1 Y[10 + #1]
G3 X[10 + #1] Y10 I#1 J0
G0 Z5

(--- 2. a ring: one full circle, G2 with the end point equal to the start ---)
G0 X30 Y100
G1 Z-#2 F300
G2 X30 Y100 I70 J0 F1500
G0 Z5

(--- 3. a five-pointed star in straight feeds ---)
G0 X100.000 Y156.000
G1 Z-#2 F300
G1 X67.084 Y54.695 F2000
G1 X153.259 Y117.305
G1 X46.741 Y117.305
G1 X132.916 Y54.695
G1 X100.000 Y156.000
G0 Z5

(--- 4. a flower of G5 cubic splines: eight petals around the centre ---)
G0 X122.000 Y100.000
G1 Z-0.6 F300
F1200
G5 I29.715 J5.435 P24.855 Q17.168 X115.556 Y115.556
G5 I17.168 J24.855 P5.435 Q29.715 X100.000 Y122.000
G5 I-5.435 J29.715 P-17.168 Q24.855 X84.444 Y115.556
G5 I-24.855 J17.168 P-29.715 Q5.435 X78.000 Y100.000
G5 I-29.715 J-5.435 P-24.855 Q-17.168 X84.444 Y84.444
G5 I-17.168 J-24.855 P-5.435 Q-29.715 X100.000 Y78.000
G5 I5.435 J-29.715 P17.168 Q-24.855 X115.556 Y84.444
G5 I24.855 J-17.168 P29.715 Q-5.435 X122.000 Y100.000
G0 Z5

(--- 5. a helix: three turns down into the centre, then a clean-up turn ---)
G0 X112 Y100
G1 Z0 F300
G2 X112 Y100 Z-3 I-12 J0 P3 F900   (P3: three full turns while Z falls 3 mm)
G2 X112 Y100 I-12 J0               (flat finishing turn at Z-3)
G0 Z5

(--- 6. four drilled marks at the corners of the ring, pecked by hand ---)
G0 X30 Y30
G1 Z-2 F200
G4 P0.2                (dwell at the bottom)
G0 Z2
G0 X170 Y30
G1 Z-2 F200
G4 P0.2                (dwell at the bottom)
G0 Z2
G0 X170 Y170
G1 Z-2 F200
G4 P0.2                (dwell at the bottom)
G0 Z2
G0 X30 Y170
G1 Z-2 F200
G4 P0.2                (dwell at the bottom)
G0 Z2

(--- done: park clear of the work ---)
G0 Z5
M9                      (coolant off)
M5                      (spindle off)
G0 X0 Y200
M30
