//! Simulated qq2drv board (work in progress).
