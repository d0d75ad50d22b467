//! # oslf-bake
//!
//! (crate docs are written at the end of the first session; see README.md)

pub mod error;
pub mod ray;

// geometry
pub mod bezier;
pub mod bvh;
pub mod mesh;
pub mod obj;
pub mod shapes;

// radiance
pub mod camera;
pub mod environment;
pub mod integrator;
pub mod light;
pub mod material;
pub mod sampling;
pub mod texture;

// the bake
pub mod bake;
pub mod capture;
pub mod image_file;
pub mod sample_map;
pub mod sample_points;
pub mod scene;

pub use error::{BakeError, Result};
