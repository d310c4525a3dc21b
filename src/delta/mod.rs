//! The prismatic delta robot of the paper: kinematics (eq. 2-8) and the Lagrangian
//! dynamics (eq. 9-14), statics (eq. 15-17) and energy (eq. 20).
