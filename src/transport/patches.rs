//! Radiosity's patches (`--method radiosity`): the diffuse part of the scene cut into small
//! pieces by area-bounded subdivision, the table that both backends read to find a point's
//! patch and to sample points on a patch, and the constants of the solve that both backends
//! share (`src/cpu/radiosity.rs` and `shaders/radiosity.wgsl`, whose host side is
//! `src/gpu/radiosity.rs`).
//!
//! Every primitive that is not a mirror or glass (diffuse surfaces, and emitters, whose
//! radiosity is their emission plus what they reflect) is cut into cells of at most
//! `A_max = (s · D)²`, with s the patch size (`--patch-size`, a share of the scene's size) and
//! D the diagonal of the scene's bounding box:
//!
//! - a triangle of area A into n² sub-triangles of a barycentric grid, n = ⌈√(A / A_max)⌉: cell
//!   (i, j) of the grid, i = ⌊b1 n⌋ and j = ⌊b2 n⌋, holds a lower triangle (frac b1 n +
//!   frac b2 n < 1) and, where i + j < n − 1, an upper one. Cells are numbered row by row,
//!   row i holding 2 (n − i) − 1 of them from i (2n − i), so the cell of barycentrics (b1, b2)
//!   is `i (2n − i) + 2j + upper`, and all n² of them have area A / n²;
//! - a sphere of area 4πr² into n_z bands of equal height in z (Archimedes: equal area) times
//!   n_φ = 2 n_z sectors, n_z = ⌈√(4πr² / (2 A_max))⌉, cell `band · n_φ + sector`.
//!
//! A triangle's cells have two sides, since diffuse surfaces here are two-sided and a wall of a
//! room is lit on one side only (patch `2 cell + back`); a sphere's cells one, the side its
//! normal points to (the inside of a flipped sphere), also for a point seen from behind. So a
//! hit point maps to its patch by a few multiplies from (primitive, barycentrics or direction
//! from the centre), with no search, on both backends (`patch_of` in `src/cpu/radiosity.rs`
//! and `shaders/radiosity.wgsl`).

use crate::layout::{
    sphere_area, triangle_area, FlatScene, Material, KIND_GLASS, KIND_MIRROR, PRIM_SPHERE_BIT,
};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// The dimension block of the form-factor rays: (point on the patch (2), direction (2)), keyed by
/// (seed, patch, ray); apart from the camera's and light subpaths' blocks.
pub const DIM_FORM_FACTOR: u32 = 0x3000_0000;

/// Jacobi stops once no patch's channel changes by more than this share in a step.
pub const JACOBI_TOLERANCE: f32 = 1e-5;

/// The most Jacobi steps: ρ = 0.95 everywhere converges in about 230.
pub const MAX_JACOBI_STEPS: u32 = 10_000;

/// The largest relative change of a channel between two steps (0 where both are 0).
#[inline]
pub fn relative_change(new: Vec3, old: Vec3) -> f32 {
    let d = (new - old).abs();
    let m = new.max(old);
    let r = Vec3::select(m.cmpgt(Vec3::ZERO), d / m, Vec3::ZERO);
    r.max_element()
}

/// Marks a primitive without patches (a mirror or glass): `PatchGrid::first`.
pub const NO_PATCHES: u32 = u32::MAX;

/// The default patch size, as a share of the scene's diagonal: measured on cornell_box
/// (docs/methods.md, "Radiosity").
pub const DEFAULT_PATCH_SIZE: f32 = 0.05;

/// Form-factor rays per patch by default (`--patch-rays`).
pub const DEFAULT_PATCH_RAYS: u32 = 1024;

/// The most patches the CPU solves: the dense form-factor matrix holds 4 N² bytes, 1 GiB at
/// N = 16384, and each Jacobi step reads all of it.
pub const MAX_PATCHES: usize = 16384;

/// What a radiosity render is asked for: the patch size (a share of the scene's diagonal,
/// `--patch-size`) and the form-factor rays per patch (`--patch-rays`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiositySettings {
    pub patch_size: f32,
    pub patch_rays: u32,
}

impl Default for RadiositySettings {
    fn default() -> Self {
        RadiositySettings {
            patch_size: DEFAULT_PATCH_SIZE,
            patch_rays: DEFAULT_PATCH_RAYS,
        }
    }
}

/// Where one primitive's patches are (triangles first, then spheres, in `FlatScene` order):
/// the first patch's index (or [`NO_PATCHES`]), the grid (a triangle's n, twice; a sphere's
/// n_z and n_φ) and the sides per cell (2 for a triangle, 1 for a sphere). One vec4.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct PatchGrid {
    pub first: u32,
    pub n: u32,
    pub m: u32,
    pub sides: u32,
}

/// One patch: its reflectance ρ and its emission Le (radiance, on an emitter's front side
/// only), the primitive (a `prims` reference), cell and side it is, and its area. Three vec4s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Patch {
    pub albedo: [f32; 3],
    pub prim: u32,
    pub emission: [f32; 3],
    pub cell: u32,
    /// 0: the side the primitive's normal points to; 1: the other.
    pub side: u32,
    pub area: f32,
    pub pad0: u32,
    pub pad1: u32,
}

/// The patch table of a scene.
#[derive(Clone, Debug, Default)]
pub struct Patches {
    /// One per triangle, then one per sphere.
    pub grids: Vec<PatchGrid>,
    pub patches: Vec<Patch>,
    /// The largest patch area asked for, `(size · diagonal)²`.
    pub max_area: f32,
}

/// Why a scene cannot be cut into patches at a size.
#[derive(Clone, Debug, PartialEq)]
pub struct TooManyPatches {
    pub patches: u64,
    pub limit: u64,
    /// What bounds it ("the CPU's 1 GiB form-factor matrix", a device's binding).
    pub why: String,
}

impl std::fmt::Display for TooManyPatches {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "radiosity would cut the scene into {} patches, and its dense form-factor matrix \
             (4 N² bytes: {:.2} GiB) fits {} patches at most ({}); raise --patch-size",
            self.patches,
            form_factor_bytes(self.patches) as f64 / (1u64 << 30) as f64,
            self.limit,
            self.why
        )
    }
}

impl std::error::Error for TooManyPatches {}

/// Bytes of the dense form-factor matrix of `n` patches, one f32 each.
pub fn form_factor_bytes(n: u64) -> u64 {
    4 * n * n
}

/// The most patches whose form-factor matrix fits `bytes`.
pub fn patches_within(bytes: u64) -> u64 {
    ((bytes / 4) as f64).sqrt().floor() as u64
}

/// A triangle's grid for cells of area at most `max_area`.
fn triangle_grid(area: f32, max_area: f32) -> u32 {
    ((area / max_area).sqrt().ceil() as u32).max(1)
}

/// A sphere's bands for cells of area at most `max_area` (twice as many sectors).
fn sphere_bands(area: f32, max_area: f32) -> u32 {
    ((area / (2.0 * max_area)).sqrt().ceil() as u32).max(1)
}

/// Whether a material's surfaces get patches: all but mirrors and glass.
pub fn has_patches(material: &Material) -> bool {
    material.kind != KIND_MIRROR && material.kind != KIND_GLASS
}

/// The scene's bounding-box diagonal, D.
pub fn scene_diagonal(scene: &FlatScene) -> f32 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in &scene.triangles {
        for v in [t.v0, t.v1, t.v2] {
            lo = lo.min(Vec3::from(v));
            hi = hi.max(Vec3::from(v));
        }
    }
    for s in &scene.spheres {
        let c = Vec3::from(s.center);
        lo = lo.min(c - s.radius);
        hi = hi.max(c + s.radius);
    }
    if lo.x > hi.x {
        return 0.0;
    }
    (hi - lo).length()
}

/// How many patches `scene` has at patch size `size` (no table is made).
pub fn count(scene: &FlatScene, size: f32) -> u64 {
    let max_area = max_area_of(scene, size);
    let tris = scene
        .triangles
        .iter()
        .filter(|t| has_patches(&scene.materials[t.material as usize]))
        .map(|t| 2 * (triangle_grid(triangle_area(t), max_area) as u64).pow(2));
    let spheres = scene
        .spheres
        .iter()
        .filter(|s| has_patches(&scene.materials[s.material as usize]))
        .map(|s| 2 * (sphere_bands(sphere_area(s), max_area) as u64).pow(2));
    tris.chain(spheres).sum()
}

fn max_area_of(scene: &FlatScene, size: f32) -> f32 {
    let edge = size * scene_diagonal(scene);
    (edge * edge).max(f32::MIN_POSITIVE)
}

/// Checks that the patches of `scene` at `size` fit `limit` patches (`why` bounds it).
pub fn check_count(
    scene: &FlatScene,
    size: f32,
    limit: u64,
    why: &str,
) -> Result<u64, TooManyPatches> {
    let n = count(scene, size);
    if n > limit {
        return Err(TooManyPatches {
            patches: n,
            limit,
            why: why.to_string(),
        });
    }
    Ok(n)
}

/// The CPU's limit on patches, as a reason for [`check_count`].
pub const CPU_LIMIT_REASON: &str = "the CPU keeps the matrix within 1 GiB";

impl Patches {
    /// Cuts the diffuse part of `scene` into patches of at most `(size · D)²` each, after
    /// checking that there are at most [`MAX_PATCHES`].
    pub fn build(scene: &FlatScene, size: f32) -> Result<Patches, TooManyPatches> {
        check_count(scene, size, MAX_PATCHES as u64, CPU_LIMIT_REASON)?;
        let max_area = max_area_of(scene, size);
        let mut grids = Vec::with_capacity(scene.triangles.len() + scene.spheres.len());
        let mut patches = Vec::new();
        let mut add = |prim: u32, material: &Material, cells: u32, sides: u32, area: f32| {
            let first = patches.len() as u32;
            for cell in 0..cells {
                for side in 0..sides {
                    // An emitter emits from its front (side 0) only.
                    let emission = if side == 0 {
                        material.emission
                    } else {
                        [0.0; 3]
                    };
                    patches.push(Patch {
                        albedo: material.color,
                        prim,
                        emission,
                        cell,
                        side,
                        area,
                        pad0: 0,
                        pad1: 0,
                    });
                }
            }
            first
        };
        for (k, t) in scene.triangles.iter().enumerate() {
            let material = &scene.materials[t.material as usize];
            if !has_patches(material) {
                grids.push(PatchGrid {
                    first: NO_PATCHES,
                    ..Default::default()
                });
                continue;
            }
            let area = triangle_area(t);
            let n = triangle_grid(area, max_area);
            let cell_area = area / (n * n) as f32;
            let first = add(k as u32, material, n * n, 2, cell_area);
            grids.push(PatchGrid {
                first,
                n,
                m: n,
                sides: 2,
            });
        }
        for (k, s) in scene.spheres.iter().enumerate() {
            let material = &scene.materials[s.material as usize];
            if !has_patches(material) {
                grids.push(PatchGrid {
                    first: NO_PATCHES,
                    ..Default::default()
                });
                continue;
            }
            let area = sphere_area(s);
            let n = sphere_bands(area, max_area);
            let cell_area = area / (2 * n * n) as f32;
            let first = add(
                k as u32 | PRIM_SPHERE_BIT,
                material,
                2 * n * n,
                1,
                cell_area,
            );
            grids.push(PatchGrid {
                first,
                n,
                m: 2 * n,
                sides: 1,
            });
        }
        Ok(Patches {
            grids,
            patches,
            max_area,
        })
    }

    pub fn len(&self) -> usize {
        self.patches.len()
    }

    pub fn is_empty(&self) -> bool {
        self.patches.is_empty()
    }

    /// The grid of primitive `prim` (a `prims` reference); `triangles` is the scene's count.
    #[inline]
    pub fn grid(&self, prim: u32, triangles: usize) -> PatchGrid {
        if prim & PRIM_SPHERE_BIT != 0 {
            self.grids[triangles + (prim & !PRIM_SPHERE_BIT) as usize]
        } else {
            self.grids[prim as usize]
        }
    }
}

/// The cell of an n x n barycentric grid that holds barycentrics (b1, b2) (see the module's
/// comment), clamped into the triangle.
#[inline]
pub fn triangle_cell(n: u32, b1: f32, b2: f32) -> u32 {
    let nf = n as f32;
    let x = (b1 * nf).max(0.0);
    let y = (b2 * nf).max(0.0);
    let i = (x as u32).min(n - 1);
    let j = (y as u32).min(n - 1 - i);
    let upper = u32::from(x - i as f32 + (y - j as f32) >= 1.0 && i + j < n - 1);
    i * (2 * n - i) + 2 * j + upper
}

/// The barycentrics (b1, b2) of the corners of cell `cell` of an n x n grid: the corner the
/// cell's two edges leave from, and the two edge vectors (in barycentric units).
#[inline]
pub fn triangle_cell_corners(n: u32, cell: u32) -> ([f32; 2], [f32; 2], [f32; 2]) {
    // Row i holds cells i (2n - i) .. (i + 1)(2n - i - 1).
    let mut i = 0;
    while (i + 1) * (2 * n - i - 1) <= cell {
        i += 1;
    }
    let k = cell - i * (2 * n - i);
    let (j, upper) = (k / 2, k % 2);
    let h = 1.0 / n as f32;
    let (x, y) = (i as f32 * h, j as f32 * h);
    if upper == 0 {
        ([x, y], [h, 0.0], [0.0, h])
    } else {
        ([x + h, y + h], [-h, 0.0], [0.0, -h])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_structs_are_whole_vec4s() {
        assert_eq!(std::mem::size_of::<PatchGrid>(), 16);
        assert_eq!(std::mem::size_of::<Patch>(), 48);
    }

    /// Every cell of a grid maps back to itself from a point inside it, and the cells are
    /// 0..n² without gaps.
    #[test]
    fn triangle_cells_round_trip() {
        for n in 1..7 {
            for cell in 0..n * n {
                let (c, e1, e2) = triangle_cell_corners(n, cell);
                // The centroid of the cell.
                let b1 = c[0] + (e1[0] + e2[0]) / 3.0;
                let b2 = c[1] + (e1[1] + e2[1]) / 3.0;
                assert_eq!(triangle_cell(n, b1, b2), cell, "n {n}");
            }
        }
    }
}
