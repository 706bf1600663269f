//! Sans-I/O codec for the `qq2drv` board (work in progress).
#![forbid(unsafe_code)]
