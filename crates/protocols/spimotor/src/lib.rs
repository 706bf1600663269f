//! Sans-I/O codec for the `spimotor` board (work in progress).
#![forbid(unsafe_code)]
