//! Sans-I/O codec for the `qsb` board (work in progress).
#![forbid(unsafe_code)]
