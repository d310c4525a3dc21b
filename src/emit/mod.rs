//! The emitter: input lines byte-for-byte, with `; delta-gcode` annotation lines added.
