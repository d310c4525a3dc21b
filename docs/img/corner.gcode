; A 90° corner at 150 mm/s with 3000 mm/s² and square_corner_velocity 5 (Klipper defaults)
G28
G1 X-40 Y-40 Z5 F6000
G4 P500
G1 X40 Y-40 F9000
G1 X40 Y40
G4 P500
