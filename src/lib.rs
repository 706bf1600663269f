//! Anchor crate of the motiond workspace.
//!
//! This package exists so that the workspace root can own the cross-crate integration tests
//! in `tests/` and the benchmarks in `benches/`. It exports nothing.
#![forbid(unsafe_code)]
