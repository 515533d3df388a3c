G1 X1 (comment
) ; tail
(((((
;;;
G0 X1 Y2 Z-1 M3
M300 S30
G20 G0 X1
G4 P0.25
G28 X1
G92 X0 Y0
M2
