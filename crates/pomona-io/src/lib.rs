//! # pomona-io
//!
//! Every file format Pomona reads or writes, converting to and from `pomona-core` types:
//!
//! * the **dataset layout** ([`Dataset`], [`DatasetWriter`], [`CameraFile`]): `camera.json`,
//!   16-bit depth PNGs, colour PNG/JPEG, truth JSON, instance masks — documented in
//!   `docs/formats.md`;
//! * **point-cloud files**: PCD (ascii, binary, binary_compressed) and PLY (ascii, binary).
//!
//! Readers validate before they allocate and report typed errors that name the file; writers go
//! through a temporary file and a rename so a failure never leaves half a file behind.

mod atomic_write;
mod camera_file;
mod dataset;
mod dataset_writer;
mod error;
mod image_file;

pub use camera_file::CameraFile;
pub use dataset::Dataset;
pub use dataset_writer::{write_json, DatasetWriter};
pub use error::DatasetError;
pub use image_file::{
    read_color_image, read_depth_png, read_mask_png, write_color_png, write_depth_png, write_mask_png,
};
