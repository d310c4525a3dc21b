; Sample for delta-gcode: an aggressive tune written to exceed the motor force limit of
; machines/kossel.yaml on purpose: 20 m/s^2 accelerations and a square corner velocity of
; 40 mm/s, so each 90-degree corner of the zig-zag changes the velocity by ~57 mm/s at once.
G28 ; home
G90 ; absolute positions
M83 ; relative extrusion
G1 Z10 F6000
G1 X-50 Y-40 F12000
SET_VELOCITY_LIMIT ACCEL=20000 SQUARE_CORNER_VELOCITY=40
G4 P0
G1 X50 Y-40 F18000
G1 X50 Y-20
G1 X-50 Y-20 F18000
G1 X-50 Y0
G1 X50 Y0 F18000
G1 X50 Y20
G1 X-50 Y20 F18000
G1 X-50 Y40
G1 X50 Y40 F18000
SET_VELOCITY_LIMIT ACCEL=3000 SQUARE_CORNER_VELOCITY=5
G1 X0 Y0 F6000
G28
