//! Simulated spimotor board (work in progress).
