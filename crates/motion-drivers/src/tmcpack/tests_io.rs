//! I/O tests of the tmcpack driver.
