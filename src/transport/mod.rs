//! The concepts of light transport that both backends share: the camera, the BSDFs, the
//! emitters, planar mirrors, the bidirectional methods' MIS quantities ([`subpath`]), the merge
//! radius ([`merging`]) and its [`clearance`], radiosity's [`patches`], splats, the [`method`] enum, and the planted
//! [`faults`] that show the tests can fail.

pub mod bsdf;
pub mod camera;
pub mod clearance;
pub mod faults;
pub mod light;
pub mod merging;
pub mod method;
pub mod patches;
pub mod planar_mirror;
pub mod splat;
pub mod subpath;
