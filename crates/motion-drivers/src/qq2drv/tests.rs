//! Unit tests of the QuadQuad2Drv driver.
