//! The arithmetic the integrators share: rays and their intersections with error bounds
//! ([`geometry`]), the counter-based random numbers and the warps ([`sampling`]), and the
//! CPU's eight-lane SIMD rows ([`lanes`]).

pub mod geometry;
pub mod lanes;
pub mod sampling;
