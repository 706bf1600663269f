//! A real motiond (see the CLI tests).
