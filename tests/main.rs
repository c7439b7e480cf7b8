//! The integration tests, one module per property file (`tests/<property>.rs`), built as one
//! test executable: each executable is a full link of the renderer and wgpu (with the release
//! profile's LTO, about half a minute each on 2 cores), so one binary instead of twenty keeps
//! `cargo test --release` quick. Run one file's tests with a filter: `cargo test --release furnace::`.

mod bad_input;
mod bdpt_references;
mod bench;
mod bidirectional_furnace;
mod bidirectional_parity;
mod chi_square;
mod clearance;
mod cli;
mod common;
mod compare;
mod crafted_files;
mod curve;
mod dark_image;
mod determinism;
mod direct_light;
mod furnace;
mod fuzz_scenes;
mod gpu_bands;
mod gpu_lost;
mod gpu_parity;
mod gpu_random;
mod independent_renderer;
mod layout;
mod light_paths;
mod light_samples;
mod light_tracing;
mod merge;
mod merge_radius;
mod meshes;
mod mis_weights;
mod module_graph;
mod nothing_lost;
mod photon_map;
mod photon_merging;
mod precision;
mod radiosity;
mod reintersect;
mod scene_parser;
mod shaders;
mod stability_caustic;
mod stability_far_from_origin;
mod stability_grazing;
mod stability_mirror;
mod stability_mirror_corridor;
mod stability_shadow_colour;
mod stability_tangent;
mod stability_thin;
mod stability_tiny_light;
mod standard_error;
mod target_error;
mod tessellation;
mod twins;
mod whitted;
