//! hexray: a physically based Monte Carlo path tracer with a WGSL compute-shader backend and a
//! CPU reference backend that follow one algorithm step by step.
//!
//! Data flows one way: a scene file is parsed and validated ([`scene`]), flattened into the
//! plain-old-data arrays both backends read ([`flat`], with its [`bvh`]), rendered
//! progressively into a [`film::Film`] of per-pixel sums ([`render`], [`cpu`]), and written as
//! EXR and PNG ([`output`]). [`stats`] holds the statistics the tests and tools share.

pub mod bench;
pub mod bsdf;
pub mod bvh;
pub mod camera;
pub mod chart;
pub mod clearance;
pub mod compare;
pub mod cpu;
pub mod curve;
pub mod film;
pub mod film_file;
pub mod flat;
pub mod geometry;
pub mod gpu;
pub mod hash_grid;
pub mod interrupt;
pub mod lanes;
pub mod light;
pub mod merge;
pub mod merging;
pub mod method;
pub mod output;
pub mod packet;
pub mod planar_mirror;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod splat;
pub mod stats;
pub mod subpath;
pub mod wide_bvh;
