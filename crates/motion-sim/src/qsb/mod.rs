//! Simulated qsb board (work in progress).
