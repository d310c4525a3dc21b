; delta-gcode sample: a fast zig-zag with a high acceleration, written to exceed
; the motor force limit of machines/kossel.yaml on purpose (M204 S20000 asks 20 m/s^2).
G28 ; home
G90 ; absolute positions
M83 ; relative extrusion
G1 Z10 F6000
G1 X-50 Y-40 F12000
M204 S20000
G4 P0
G1 X50 Y-40 F24000
G1 X50 Y-20
G1 X-50 Y-20 F24000
G1 X-50 Y0
G1 X50 Y0 F24000
G1 X50 Y20
G1 X-50 Y20 F24000
G1 X-50 Y40
G1 X50 Y40 F24000
M204 S3000
G1 X0 Y0 F6000
G28
