//! # pomona-io
//!
//! Every file format Pomona reads or writes, converting to and from `pomona-core` types:
//!
//! * the **dataset layout** ([`Dataset`], [`DatasetWriter`], [`CameraFile`]): `camera.json`,
//!   16-bit depth PNGs, colour PNG/JPEG, truth JSON, instance masks — documented in
//!   `docs/formats.md`;
//! * **point-cloud files**: PCD (ascii, binary, binary_compressed) and PLY (ascii, binary little- and big-endian).
//!
//! Readers validate before they allocate and report typed errors that name the file; writers go
//! through a temporary file and a rename so a failure never leaves half a file behind.

mod atomic_write;
mod camera_file;
pub mod cloud_file;
mod dataset;
mod dataset_writer;
mod error;
#[doc(hidden)]
pub mod fuzzing;
mod image_file;
pub mod lzf;
pub mod pcd;
pub mod ply;
pub mod read_budget;

pub use camera_file::CameraFile;
pub use cloud_file::{read_cloud, write_cloud, CloudFileError, CloudFormat};
pub use dataset::Dataset;
pub use dataset_writer::{write_json, write_json_compact, DatasetWriter};
pub use error::DatasetError;
pub use image_file::{
    read_color_image, read_depth_png, read_mask_png, write_color_png, write_depth_png,
    write_mask_png,
};
pub use pcd::{read_pcd, read_pcd_file, write_pcd, PcdEncoding, PcdError, PcdHeader};
pub use ply::{read_ply, read_ply_file, write_ply, PlyEncoding, PlyError};
