//! Acceleration structures: the four-wide BVH both backends traverse ([`bvh`]), the CPU's
//! eight-wide collapse of it ([`wide_bvh`]) and its packet traversal ([`packet`]), and the hash
//! grid of light vertices for photon merging ([`hash_grid`]).

pub mod bvh;
pub mod hash_grid;
pub mod packet;
pub mod wide_bvh;
