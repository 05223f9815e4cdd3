//! One module per subcommand.

pub mod cloud;
pub mod convert;
pub mod eval;
pub mod info;
pub mod synth;
