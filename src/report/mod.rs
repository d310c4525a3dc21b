//! Per-move statistics and the report, with its text, JSON and GitHub writers.
