; Sample for delta-gcode: a speed tune this Kossel Mini's motors cannot follow. Long travel
; moves across the print disc at 400 mm/s with 10 m/s^2 accelerations: near the edge a
; carriage runs 1.3 times the nozzle's speed, past the ~460 mm/s where its 12 V motor has no
; force left.
G28 ; home
G90 ; absolute positions
M83 ; relative extrusion
G1 Z10 F6000
G1 X-70 Y-40 F12000
SET_VELOCITY_LIMIT VELOCITY=400 ACCEL=10000
G0 X70 Y-40 F24000
G0 X-70 Y40
G0 X70 Y40
G0 X0 Y-80
G0 X0 Y80
G0 X-70 Y-40
G0 X70 Y40
SET_VELOCITY_LIMIT VELOCITY=300 ACCEL=3000
G1 X0 Y0 F6000
G1 X10 Y0 Z0.3 F3000
G1 X40 Y0 E1.2 F1800
G28
