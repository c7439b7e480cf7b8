//! The shared flattened scene: plain-old-data arrays that the CPU integrator traverses and the
//! WGSL shader reads byte for byte.
//!
//! Every struct here has a twin of the same name in `shaders/scene.wgsl`, and a test compares
//! their sizes and field offsets with naga's reflection of the WGSL, so the two cannot drift.
//! The layouts follow WGSL's storage-buffer rules: a `vec3<f32>` is 16-byte aligned and a scalar
//! may fill its fourth lane, so each struct is a whole number of vec4s.

pub mod cpu;

use bytemuck::{Pod, Zeroable};
pub use cpu::{TrianglePack, WideNode};
use glam::{DVec3, Vec3};

/// Material kinds (`Material::kind`).
pub const KIND_DIFFUSE: u32 = 0;
pub const KIND_MIRROR: u32 = 1;
pub const KIND_GLASS: u32 = 2;
pub const KIND_EMITTER: u32 = 3;

/// Marks a triangle that is not in the emitter table (`Triangle::emitter`).
pub const NOT_AN_EMITTER: u32 = u32::MAX;

/// A primitive reference in `FlatScene::prims`: the index of a triangle, or of a sphere with this
/// bit set. [`PRIM_PADDING`] has this bit set too: code that reads `prims` other than through
/// a leaf's range must test for padding first.
pub const PRIM_SPHERE_BIT: u32 = 1 << 31;

/// An entry of `FlatScene::prims` that no leaf covers: the gap before a leaf that starts at the
/// next multiple of four (`bvh::flatten`).
pub const PRIM_PADDING: u32 = u32::MAX;

/// A triangle: vertices as given (the winding fixes an emitter's front), its material, its row
/// in the emitter table, the planar mirror it belongs to, and its unit normal, computed once
/// here rather than at every hit (a cross product and a square root that would sit on every
/// path vertex's critical path). Four vec4s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Triangle {
    pub v0: [f32; 3],
    pub material: u32,
    pub v1: [f32; 3],
    pub emitter: u32,
    pub v2: [f32; 3],
    /// The index in `FlatScene::planar_mirrors` of the planar mirror this triangle is part of,
    /// or `planar_mirror::NO_PLANAR_MIRROR` (`planar_mirror::find` sets it).
    pub planar_mirror: u32,
    /// Unit geometric normal, (v1 - v0) x (v2 - v0) normalised (in f64, rounded once).
    pub n: [f32; 3],
    pub pad1: u32,
}

impl Triangle {
    /// A triangle of material `material`, not an emitter (until the emitter table says so), with
    /// its unit normal.
    pub fn new(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3], material: u32) -> Triangle {
        let (a, b, c) = (
            DVec3::from(v0.map(f64::from)),
            DVec3::from(v1.map(f64::from)),
            DVec3::from(v2.map(f64::from)),
        );
        Triangle {
            v0,
            material,
            v1,
            emitter: NOT_AN_EMITTER,
            v2,
            planar_mirror: NO_PLANAR_MIRROR,
            n: (b - a).cross(c - a).normalize().as_vec3().into(),
            pad1: 0,
        }
    }
}

/// A sphere: its row in the emitter table (as a triangle's), and whether its normals point
/// inward (`flip`, 1 or 0; Mitsuba's `flip_normals`), which makes an emitting sphere light its
/// inside. Two vec4s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Sphere {
    pub center: [f32; 3],
    pub radius: f32,
    pub material: u32,
    pub emitter: u32,
    pub flip: u32,
    pub pad0: u32,
}

impl Default for Sphere {
    fn default() -> Sphere {
        Sphere {
            center: [0.0; 3],
            radius: 0.0,
            material: 0,
            emitter: NOT_AN_EMITTER,
            flip: 0,
            pad0: 0,
        }
    }
}

impl Sphere {
    /// The unit normal at a unit direction `d` from the centre: `d`, or `-d` when flipped.
    #[inline]
    pub fn normal(&self, d: Vec3) -> Vec3 {
        if self.flip != 0 {
            -d
        } else {
            d
        }
    }
}

/// A material: `color` is the albedo (diffuse, and an emitter's optional reflectance), the
/// reflectance (mirror) or the tint (glass); `emission` is an emitter's radiance. Two vec4s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Material {
    pub color: [f32; 3],
    pub kind: u32,
    pub emission: [f32; 3],
    pub ior: f32,
}

/// One row of the emitter table: a primitive that emits (a `prims` reference: a triangle's
/// index, or a sphere's with [`PRIM_SPHERE_BIT`]), its area, and the discrete distribution that
/// picks emitters in proportion to their power (area x mean radiance). One vec4.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Emitter {
    pub prim: u32,
    pub area: f32,
    /// Cumulative probability up to and including this row; the last row holds exactly 1.
    pub cdf: f32,
    /// The probability of choosing this row.
    pub pmf: f32,
}

/// A BVH node with up to four children (a "BVH4", as Embree builds),
/// in depth-first order from the root (node 0). The children's boxes are stored as a structure
/// of arrays, one row per plane, so that one four-wide operation per plane tests all four
/// children (on the CPU in SSE/NEON lanes, in WGSL as `vec4<f32>`) and one node fetch serves all
/// four box tests. Leaves are not nodes: per child slot c, `count[c]` > 0 is a leaf of
/// `count[c]` entries of `prims` from `child[c]`, `count[c]` == 0 is the interior node
/// `child[c]`, and `count[c]` == [`EMPTY_SLOT`] is an unused slot. Eight vec4s.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct BvhNode {
    /// Minimum x of the four children's boxes.
    pub min_x: [f32; 4],
    /// Maximum x of the four children's boxes.
    pub max_x: [f32; 4],
    pub min_y: [f32; 4],
    pub max_y: [f32; 4],
    pub min_z: [f32; 4],
    pub max_z: [f32; 4],
    /// Per child: an interior node's index, or a leaf's first entry in `prims`.
    pub child: [u32; 4],
    /// Per child: the leaf's number of primitives, 0 for an interior node, or [`EMPTY_SLOT`].
    pub count: [u32; 4],
}

/// `BvhNode::count` of a child slot that holds nothing (a node with fewer than four children).
pub const EMPTY_SLOT: u32 = u32::MAX;

impl BvhNode {
    /// The box of child slot `c` as (min, max).
    pub fn child_bounds(&self, c: usize) -> (Vec3, Vec3) {
        (
            Vec3::new(self.min_x[c], self.min_y[c], self.min_z[c]),
            Vec3::new(self.max_x[c], self.max_y[c], self.max_z[c]),
        )
    }
}

/// The most planar mirrors a scene keeps (the largest by area): each costs a closest-hit ray
/// per diffuse vertex whose mirror point falls in its bounds.
pub const MAX_PLANAR_MIRRORS: u32 = 4;

/// Marks a triangle on no planar mirror (`Triangle::planar_mirror`).
pub const NO_PLANAR_MIRROR: u32 = u32::MAX;

/// A planar mirror (`crate::transport::planar_mirror`): the plane n · p = d of a set of mirror
/// triangles of one material, their bounds, and how far from the plane a vertex of theirs may lie.
/// Three vec4s; the shader reads them from `Frame::planar_mirrors`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct PlanarMirror {
    pub n: [f32; 3],
    pub d: f32,
    pub lo: [f32; 3],
    pub tolerance: f32,
    pub hi: [f32; 3],
    pub material: u32,
}

/// Everything the integrators read, in the layout both backends share.
#[derive(Clone, Debug, Default)]
pub struct FlatScene {
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
    pub materials: Vec<Material>,
    pub emitters: Vec<Emitter>,
    pub nodes: Vec<BvhNode>,
    pub prims: Vec<u32>,
    /// The CPU's alone: the leaves' triangles four to a SIMD pack (`bvh::triangle_packs`),
    /// derived from `triangles` and `prims`; the shader reads those instead.
    pub packs: Vec<TrianglePack>,
    /// The CPU's alone: the tree collapsed to eight-wide nodes (`bvh::build_trees`), which the
    /// CPU traverses; the shader traverses `nodes`.
    pub wide: Vec<WideNode>,
    /// Seconds the BVH build took (`bvh::build`, not the SIMD packs), for logs.
    pub bvh_seconds: f64,
    /// The planar mirrors (`planar_mirror::find`), largest first.
    pub planar_mirrors: Vec<PlanarMirror>,
}

impl FlatScene {
    /// The bounding box of the whole scene: the union of the root's children.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let root = &self.nodes[0];
        (0..4)
            .filter(|&c| root.count[c] != EMPTY_SLOT)
            .map(|c| root.child_bounds(c))
            .fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
            )
    }
}

/// Area of a sphere in f32, 4 pi r^2.
pub fn sphere_area(s: &Sphere) -> f32 {
    4.0 * std::f32::consts::PI * s.radius * s.radius
}

/// Area of a triangle in f32, as the integrators compute it.
pub fn triangle_area(t: &Triangle) -> f32 {
    let (v0, v1, v2) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
    0.5 * (v1 - v0).cross(v2 - v0).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_structs_are_whole_vec4s() {
        assert_eq!(std::mem::size_of::<Triangle>(), 64);
        assert_eq!(std::mem::size_of::<Sphere>(), 32);
        assert_eq!(std::mem::size_of::<Material>(), 32);
        assert_eq!(std::mem::size_of::<Emitter>(), 16);
        assert_eq!(std::mem::size_of::<BvhNode>(), 128);
    }
}
