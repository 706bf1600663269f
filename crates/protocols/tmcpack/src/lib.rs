//! Sans-I/O codec for the `tmcpack` board (work in progress).
#![forbid(unsafe_code)]
