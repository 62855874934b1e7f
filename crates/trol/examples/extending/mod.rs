//! The guide's commands (docs/extending.md), shared by its examples and tests; each program
//! uses its side of them.
#[allow(dead_code)]
pub mod commands;
