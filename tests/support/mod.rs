//! Shared support of the cross-crate tests.
#![allow(dead_code)]

pub mod counting_alloc;
pub mod hold;
pub mod lag;
pub mod rig;
pub mod wire;
