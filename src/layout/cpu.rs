//! The CPU's own forms of the layout, derived from the shared arrays when a scene is flattened:
//! the leaves' triangles four to a SIMD pack, and the BVH collapsed to eight-wide nodes. The
//! shader reads neither.

use super::{Triangle, EMPTY_SLOT};
use glam::{Vec3, Vec4};

/// Up to four triangles of one BVH leaf as a structure of arrays (one `Vec4` per coordinate,
/// one lane per triangle), with the edges `e1 = v1 - v0` and `e2 = v2 - v0` stored rounded
/// exactly as [`intersect_triangle`] rounds them, so that [`intersect_triangles4`] tests the four
/// in SIMD lanes with the same arithmetic. Built by the BVH for the CPU only
/// (`FlatScene::packs`); the shader tests a leaf's triangles one at a time. A lane that holds no
/// triangle has zero edges (det = 0 never hits); `spheres` marks the lanes whose primitive is a
/// sphere, tested one by one after the triangles.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct TrianglePack {
    pub v0: [Vec4; 3],
    pub e1: [Vec4; 3],
    pub e2: [Vec4; 3],
    pub spheres: u32,
    /// The lanes that hold a triangle (a pack of spheres alone skips the four-lane test).
    pub triangles: u32,
}

impl Default for TrianglePack {
    fn default() -> Self {
        TrianglePack {
            v0: [Vec4::ZERO; 3],
            e1: [Vec4::ZERO; 3],
            e2: [Vec4::ZERO; 3],
            spheres: 0,
            triangles: 0,
        }
    }
}

impl TrianglePack {
    /// Puts `tri` in lane `lane`.
    pub fn set_triangle(&mut self, lane: usize, tri: &Triangle) {
        let v0 = Vec3::from(tri.v0);
        let e1 = Vec3::from(tri.v1) - v0;
        let e2 = Vec3::from(tri.v2) - v0;
        for axis in 0..3 {
            self.v0[axis][lane] = v0[axis];
            self.e1[axis][lane] = e1[axis];
            self.e2[axis][lane] = e2[axis];
        }
        self.triangles |= 1 << lane;
    }
}

/// The slots of a wide node.
pub const WIDTH: usize = 8;
/// Its rows of four slots, each one four-wide slab test.
pub const ROWS: usize = WIDTH / 4;

/// Eight child boxes as structure of arrays (two four-wide halves), and per child an interior
/// node's index in the wide array or a leaf's first entry in `prims` with its count, as in
/// [`BvhNode`] (count 0: interior; [`EMPTY_SLOT`]: nothing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WideNode {
    pub min_x: [Vec4; ROWS],
    pub max_x: [Vec4; ROWS],
    pub min_y: [Vec4; ROWS],
    pub max_y: [Vec4; ROWS],
    pub min_z: [Vec4; ROWS],
    pub max_z: [Vec4; ROWS],
    pub child: [u32; WIDTH],
    pub count: [u32; WIDTH],
}

impl WideNode {
    /// Slot `c`'s box (min, max).
    pub fn child_bounds(&self, c: usize) -> (Vec3, Vec3) {
        let (h, l) = (c / 4, c % 4);
        (
            Vec3::new(self.min_x[h][l], self.min_y[h][l], self.min_z[h][l]),
            Vec3::new(self.max_x[h][l], self.max_y[h][l], self.max_z[h][l]),
        )
    }
}

impl Default for WideNode {
    /// A node of empty slots: inverted boxes, which no ray enters.
    fn default() -> Self {
        let (lo, hi) = ([Vec4::INFINITY; ROWS], [Vec4::NEG_INFINITY; ROWS]);
        WideNode {
            min_x: lo,
            max_x: hi,
            min_y: lo,
            max_y: hi,
            min_z: lo,
            max_z: hi,
            child: [0; WIDTH],
            count: [EMPTY_SLOT; WIDTH],
        }
    }
}
