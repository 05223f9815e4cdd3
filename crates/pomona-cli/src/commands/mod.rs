//! One module per subcommand.

pub mod arm;
pub mod calibrate;
pub mod cloud;
pub mod convert;
pub mod demo;
pub mod detect;
pub mod eval;
pub mod experiment;
pub mod extract;
pub mod info;
pub mod plan;
pub mod ros;
pub mod stereo;
pub mod stereo_report;
pub mod synth;
pub mod track;
pub mod train;
