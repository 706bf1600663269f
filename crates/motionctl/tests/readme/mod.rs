//! The README checked against the repository (`tests/readme_commands.rs`): its markdown,
//! the shell lines of its command blocks, the clap help pages of the project's binaries,
//! the workspace's packages, and the check of one command.

pub mod check;
pub mod help;
pub mod markdown;
pub mod shell;
pub mod workspace;
