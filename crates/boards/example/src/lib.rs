//! The worked example of a motiond board.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod codec;
pub mod driver;
pub mod sim;

use motion_base::{LinkKind, Model, ModelFacts};

/// The AS-2's facts.
pub static FACTS: ModelFacts = ModelFacts {
    id: "example",
    code: 5,
    link_kind: LinkKind::Stream,
    title: "AS-2 ASCII stepper (worked example)",
};

/// The AS-2 as a model.
pub const MODEL: Model = Model::new(&FACTS);
