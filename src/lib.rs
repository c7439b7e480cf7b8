//! hexray: a physically based Monte Carlo renderer with a WGSL compute-shader backend and a
//! CPU reference backend that follow one algorithm step by step.
//!
//! Data flows one way: a scene file is parsed and validated ([`scene`]), flattened
//! ([`flatten`]) into the plain-data [`layout`] both backends read, rendered progressively
//! ([`render`], on [`cpu`] or [`gpu`]) into a [`film::Film`] of per-pixel sums, and written as
//! EXR and PNG ([`film::output`]). [`analysis`] holds the statistics, comparisons, curves and
//! benchmarks that the tests and tools share.
//!
//! The modules form layers; a module imports only from the layers below its own (`cpu` and
//! `gpu` are siblings and never import each other). `tests/module_graph.rs` checks it.
//!
//! | layer | modules |
//! |---|---|
//! | 0 | [`scene`], [`interrupt`] |
//! | 1 | [`layout`] |
//! | 2 | [`math`] |
//! | 3 | [`accel`] |
//! | 4 | [`transport`] |
//! | 5 | [`flatten`] |
//! | 6 | [`film`] |
//! | 7 | [`cpu`], [`gpu`] |
//! | 8 | [`render`] |
//! | 9 | [`analysis`] |

pub mod accel;
pub mod analysis;
pub mod cpu;
pub mod film;
pub mod flatten;
pub mod gpu;
pub mod interrupt;
pub mod layout;
pub mod math;
pub mod render;
pub mod scene;
pub mod transport;
