//! Radiosity (`--method radiosity`): the diffuse light of the scene solved once, view
//! independently, on patches (`crate::transport::patches`), then an image that takes direct
//! light by next-event estimation and the indirect diffuse light from the patch solution.
//!
//! `shaders/radiosity.wgsl` is this file again, with the same names, the same steps in the same
//! order and the same step comments; the GPU's host side is `src/gpu/radiosity.rs`.
//!
//! The solution, in radiance units (B = π L for a diffuse surface), is the discrete radiosity
//! equation L_i = Le_i + ρ_i Σ_j F_ij L_j (Cohen and Wallace, "Radiosity and Realistic Image
//! Synthesis", eq. 2.6), with F_ij the form factor from patch i to patch j:
//!
//! 1. form factors by Monte Carlo ray casting: R rays per patch i (`--patch-rays`), each from a
//!    uniform point on patch i in a cosine-distributed direction about the patch's side, so
//!    that F_ij is the share of those rays whose first hit is patch j (visibility counted).
//!    A ray that meets a mirror or glass, or leaves the scene, is lost: radiosity leaves out
//!    light that reaches a diffuse surface by way of a mirror or glass. Ray r of patch i draws
//!    `Sampler::new(seed, i, r).draw4(DIM_FORM_FACTOR)`, the same numbers on both backends;
//! 2. Jacobi (gathering) iterations from L⁰ = Le, L^(k+1)_i = Le_i + ρ_i Σ_j F_ij L^k_j, until
//!    the largest relative change of a patch's channel is below `JACOBI_TOLERANCE` (or
//!    `MAX_JACOBI_STEPS`). With row sums ≤ 1 the iteration converges as ρ^k; the error left
//!    is about the last change times ρ / (1 − ρ);
//! 3. each patch's indirect light: the light that has bounced off at least one diffuse surface
//!    before it leaves patch i, L_ind,i = ρ_i Σ_j F_ij (L_j − Le_j) (= ρ_i/π Σ_j F_ij (B_j − E_j)
//!    in radiosities), constant over the patch;
//! 4. the image: camera rays through mirrors and glass as Whitted's (`crate::cpu::whitted`) to
//!    the first diffuse surface, where direct light comes from next-event estimation (sharp
//!    shadows) and the indirect light from step 3: the direct part is not counted twice.
//!
//! So the image is biased by the discretisation (the indirect light is constant over each
//! patch, and F is estimated with R rays) and by what it leaves out: caustics, and the
//! indirect light that passes a mirror or glass before reaching a diffuse surface.

use crate::accel::bvh::{intersect_closest, occluded};
use crate::cpu::whitted::WHITTED_MAX_DEPTH;
use crate::layout::{FlatScene, Triangle, KIND_EMITTER, KIND_GLASS, KIND_MIRROR, PRIM_SPHERE_BIT};
use crate::math::geometry::{offset_ray_origin, sphere_point_at, triangle_hit_point, Ray};
use crate::math::sampling::{
    dim_light, orthonormal_basis, sample_cosine_hemisphere, sample_uniform_sphere,
    sample_uniform_triangle, sin_cos_turns, Sampler, DIM_CAMERA,
};
use crate::transport::bsdf::{fresnel_dielectric, is_diffuse, reflect, refract};
use crate::transport::camera::Camera;
use crate::transport::faults::Faults;
use crate::transport::light::{link_to_emitter, sample_emitter};
use crate::transport::patches::{
    has_patches, relative_change, triangle_cell, triangle_cell_corners, Patch, Patches,
    DIM_FORM_FACTOR, JACOBI_TOLERANCE, MAX_JACOBI_STEPS,
};
use arrayvec::ArrayVec;
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use std::time::Instant;

/// The radiosity solution of a scene: its patches, their form factors (row-major, N x N), their
/// radiance L_i, and the indirect light of step 3.
#[derive(Clone, Debug, Default)]
pub struct Solution {
    pub patches: Patches,
    pub form_factors: Vec<f32>,
    pub radiance: Vec<Vec3>,
    pub indirect: Vec<Vec3>,
    /// Jacobi steps taken, and whether the change fell below the tolerance.
    pub steps: u32,
    pub converged: bool,
    /// Seconds of the form factors and of the rest of the solve.
    pub form_factor_seconds: f64,
    pub solve_seconds: f64,
}

/// The barycentrics (b1, b2) of a point p in (or next to) a triangle's plane.
#[inline]
fn barycentrics(tri: &Triangle, p: Vec3) -> (f32, f32) {
    let v0 = Vec3::from(tri.v0);
    let e1 = Vec3::from(tri.v1) - v0;
    let e2 = Vec3::from(tri.v2) - v0;
    let d = p - v0;
    let n = e1.cross(e2);
    let inv = 1.0 / n.dot(n);
    (d.cross(e2).dot(n) * inv, e1.cross(d).dot(n) * inv)
}

/// The cell of a sphere's n_z x n_φ grid that holds the unit direction d from its centre.
#[inline]
fn sphere_cell(n: u32, m: u32, d: Vec3) -> u32 {
    let band = (((1.0 - d.z) * 0.5 * n as f32).max(0.0) as u32).min(n - 1);
    let mut turns = d.y.atan2(d.x) * (0.5 * FRAC_1_PI);
    if turns < 0.0 {
        turns += 1.0;
    }
    let sector = ((turns * m as f32).max(0.0) as u32).min(m - 1);
    band * m + sector
}

/// The patch of the point p on primitive `prim` (a `prims` reference), seen from the back
/// (`back`) or the front of a triangle.
#[inline]
pub fn patch_of(scene: &FlatScene, patches: &Patches, prim: u32, p: Vec3, back: bool) -> u32 {
    let grid = patches.grid(prim, scene.triangles.len());
    let cell = if prim & PRIM_SPHERE_BIT != 0 {
        let s = &scene.spheres[(prim & !PRIM_SPHERE_BIT) as usize];
        sphere_cell(grid.n, grid.m, (p - Vec3::from(s.center)) / s.radius)
    } else {
        let (b1, b2) = barycentrics(&scene.triangles[prim as usize], p);
        triangle_cell(grid.n, b1, b2)
    };
    grid.first + cell * grid.sides + u32::from(back).min(grid.sides - 1)
}

/// A point on patch `pt` from (u1, u2), uniform over its area: the point, its error bound, and
/// the unit normal of the patch's side.
#[inline]
fn patch_point(
    scene: &FlatScene,
    patches: &Patches,
    pt: &Patch,
    u1: f32,
    u2: f32,
) -> (Vec3, Vec3, Vec3) {
    let grid = patches.grid(pt.prim, scene.triangles.len());
    if pt.prim & PRIM_SPHERE_BIT != 0 {
        let s = &scene.spheres[(pt.prim & !PRIM_SPHERE_BIT) as usize];
        // z uniform within the band, φ within the sector: uniform in area (Archimedes).
        let (band, sector) = (pt.cell / grid.m, pt.cell % grid.m);
        let z = 1.0 - 2.0 * (band as f32 + u1) / grid.n as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let (sin_phi, cos_phi) = sin_cos_turns((sector as f32 + u2) / grid.m as f32);
        let d = Vec3::new(r * cos_phi, r * sin_phi, z);
        let (p, p_err) = sphere_point_at(s, s.radius * d);
        return (p, p_err, s.normal(d));
    }
    let tri = &scene.triangles[pt.prim as usize];
    let (c, e1, e2) = triangle_cell_corners(grid.n, pt.cell);
    let (_, s, t) = sample_uniform_triangle(u1, u2);
    let b1 = c[0] + s * e1[0] + t * e2[0];
    let b2 = c[1] + s * e1[1] + t * e2[1];
    let (p, p_err) = triangle_hit_point(tri, b1, b2);
    let n = Vec3::from(tri.n);
    (p, p_err, if pt.side == 0 { n } else { -n })
}

/// Row i of the form factors: step 1 for patch i, added to `row` (N entries). Returns the rays
/// traced.
pub fn form_factor_row(
    scene: &FlatScene,
    patches: &Patches,
    i: u32,
    seed: u32,
    rays: u32,
    faults: Faults,
    row: &mut [f32],
) -> u64 {
    // Step 1 - form factors: R rays from uniform points on patch i, cosine-distributed about
    // its side; the patch each first meets gets 1 / R (mirrors, glass and misses lose theirs).
    let pt = patches.patches[i as usize];
    let weight = faults.form_factor_scale / rays as f32;
    for r in 0..rays {
        let u = Sampler::new(seed, i, r).draw4(DIM_FORM_FACTOR);
        let (p, p_err, n) = patch_point(scene, patches, &pt, u[0], u[1]);
        let local = if faults.form_factor_uniform_directions {
            let d = sample_uniform_sphere(u[2], u[3]);
            Vec3::new(d.x, d.y, d.z.abs())
        } else {
            sample_cosine_hemisphere(u[2], u[3])
        };
        let (t, b) = orthonormal_basis(n);
        let d = local.x * t + local.y * b + local.z * n;
        let ray = Ray {
            o: offset_ray_origin(p, p_err, n, d),
            d,
        };
        let Some(hit) = intersect_closest(scene, &ray, f32::MAX) else {
            continue;
        };
        if !has_patches(&scene.materials[hit.material as usize]) {
            continue;
        }
        let j = patch_of(scene, patches, hit.prim, hit.p, hit.n.dot(d) > 0.0);
        row[j as usize] += weight;
    }
    rays as u64
}

/// One Jacobi step for patch i: Le_i + ρ_i Σ_j F_ij L_j, summed in order of j.
#[inline]
fn jacobi_step(patches: &Patches, form_factors: &[f32], radiance: &[Vec3], i: usize) -> Vec3 {
    // Step 2 - Jacobi: L_i = Le_i + ρ_i Σ_j F_ij L_j from the previous step's L.
    let n = patches.len();
    let row = &form_factors[i * n..(i + 1) * n];
    let mut sum = Vec3::ZERO;
    for (f, l) in row.iter().zip(radiance) {
        sum += *f * *l;
    }
    let pt = &patches.patches[i];
    Vec3::from(pt.emission) + Vec3::from(pt.albedo) * sum
}

/// Patch i's indirect light, ρ_i Σ_j F_ij (L_j − Le_j).
#[inline]
fn gather_indirect(
    patches: &Patches,
    form_factors: &[f32],
    radiance: &[Vec3],
    i: usize,
    faults: Faults,
) -> Vec3 {
    // Step 3 - indirect light: what reaches patch i from the other patches but their
    // emission (next-event estimation takes that), reflected: ρ_i Σ_j F_ij (L_j − Le_j).
    let n = patches.len();
    let row = &form_factors[i * n..(i + 1) * n];
    let mut sum = Vec3::ZERO;
    for (j, (f, l)) in row.iter().zip(radiance).enumerate() {
        let emitted = if faults.indirect_with_direct {
            Vec3::ZERO
        } else {
            Vec3::from(patches.patches[j].emission)
        };
        sum += *f * (*l - emitted);
    }
    Vec3::from(patches.patches[i].albedo) * sum
}

/// Solves the scene's radiosity on `patches` (steps 1-3) with `rays` form-factor rays per patch
/// and the random streams of `seed`, on the current rayon pool. Returns the solution and the
/// rays traced.
pub fn solve(
    scene: &FlatScene,
    patches: Patches,
    seed: u32,
    rays: u32,
    faults: Faults,
) -> (Solution, u64) {
    let n = patches.len();
    let start = Instant::now();
    let mut form_factors = vec![0.0f32; n * n];
    let traced: u64 = form_factors
        .par_chunks_mut(n.max(1))
        .enumerate()
        .map(|(i, row)| form_factor_row(scene, &patches, i as u32, seed, rays, faults, row))
        .sum();
    let form_factor_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let mut radiance: Vec<Vec3> = patches
        .patches
        .iter()
        .map(|p| Vec3::from(p.emission))
        .collect();
    let mut steps = 0;
    let mut converged = false;
    while steps < MAX_JACOBI_STEPS && n > 0 {
        let next: Vec<Vec3> = (0..n)
            .into_par_iter()
            .map(|i| jacobi_step(&patches, &form_factors, &radiance, i))
            .collect();
        let change = next
            .iter()
            .zip(&radiance)
            .map(|(a, b)| relative_change(*a, *b))
            .fold(0.0f32, f32::max);
        radiance = next;
        steps += 1;
        if change < JACOBI_TOLERANCE {
            converged = true;
            break;
        }
    }
    let indirect = (0..n)
        .into_par_iter()
        .map(|i| gather_indirect(&patches, &form_factors, &radiance, i, faults))
        .collect();
    let solution = Solution {
        patches,
        form_factors,
        radiance,
        indirect,
        steps,
        converged,
        form_factor_seconds,
        solve_seconds: start.elapsed().as_secs_f64(),
    };
    (solution, traced)
}

/// One ray of the tree, as Whitted's: where it goes, what it carries and how many specular
/// bounces led to it.
#[derive(Clone, Copy, Debug)]
struct Branch {
    ray: Ray,
    weight: Vec3,
    depth: u32,
}

/// The radiance arriving at pixel (x, y) along one camera sample's ray tree, with the solution's
/// indirect light at each diffuse surface. `rays` counts the rays traced.
#[allow(clippy::too_many_arguments)]
pub fn trace_radiosity(
    scene: &FlatScene,
    camera: &Camera,
    solution: &Solution,
    x: u32,
    y: u32,
    sampler: &Sampler,
    faults: Faults,
    rays: &mut u64,
) -> Vec3 {
    // Step 4 - the image: Whitted's ray tree (camera ray, then both branches at glass, to
    // WHITTED_MAX_DEPTH specular bounces), walked depth first in the same order.
    let u_camera = sampler.draw4(DIM_CAMERA);
    let mut stack = ArrayVec::<Branch, { WHITTED_MAX_DEPTH as usize + 1 }>::new();
    stack.push(Branch {
        ray: camera.ray(x, y, u_camera[0], u_camera[1]),
        weight: Vec3::ONE,
        depth: 0,
    });
    let mut radiance = Vec3::ZERO;
    let mut branch = 0u32;
    while let Some(b) = stack.pop() {
        let index = branch;
        branch += 1;

        // Step 4a - closest hit: the nearest surface along the ray; a miss sees nothing.
        *rays += 1;
        let Some(hit) = intersect_closest(scene, &b.ray, f32::MAX) else {
            continue;
        };
        let material = scene.materials[hit.material as usize];
        let wo = -b.ray.d;
        let cos_o = hit.n.dot(wo);

        // Step 4b - emission: an emitter seen from its front, straight or in mirrors and glass.
        if material.kind == KIND_EMITTER && cos_o > 0.0 {
            radiance += b.weight * Vec3::from(material.emission);
        }

        // Step 4c - diffuse surfaces: direct light by one point on the emitters and one shadow
        // ray (f · Le · cos θs / p_ω), plus the indirect light of the patch seen, from its side.
        // The branch ends here.
        if is_diffuse(&material) {
            let u = sampler.draw4(dim_light(index));
            let n_facing = if cos_o < 0.0 { -hit.n } else { hit.n };
            let ls = sample_emitter(scene, u[0], u[1], u[2]);
            if let Some(link) = link_to_emitter(hit.p, hit.p_err, hit.n, n_facing, &ls) {
                *rays += 1;
                if !occluded(scene, &link.shadow, 1.0) {
                    let f = Vec3::from(material.color) * FRAC_1_PI;
                    radiance += b.weight * f * link.le * (link.cos_s / link.light_pdf);
                }
            }
            let pt = patch_of(scene, &solution.patches, hit.prim, hit.p, cos_o < 0.0);
            radiance += b.weight * solution.indirect[pt as usize];
            continue;
        }

        // Step 4d - perfect specular, as Whitted's: a mirror reflects with its reflectance;
        // glass reflects with F and refracts with (1 - F) · tint / η², both followed (the
        // refraction first). A black emitter ends the branch.
        if b.depth >= WHITTED_MAX_DEPTH {
            continue;
        }
        let weight = b.weight * faults.specular_scale;
        let mut follow = |wi: Vec3, w: Vec3| {
            if w.max_element() > 0.0 {
                stack.push(Branch {
                    ray: Ray {
                        o: offset_ray_origin(hit.p, hit.p_err, hit.n, wi),
                        d: wi,
                    },
                    weight: w,
                    depth: b.depth + 1,
                });
            }
        };
        if material.kind == KIND_MIRROR {
            follow(reflect(wo, hit.n), weight * Vec3::from(material.color));
        } else if material.kind == KIND_GLASS {
            let f = fresnel_dielectric(cos_o, material.ior);
            follow(reflect(wo, hit.n), weight * f);
            if let Some((wt, etap)) = refract(wo, hit.n, material.ior) {
                let tint = Vec3::from(material.color);
                follow(wt, weight * (1.0 - f) * tint / (etap * etap));
            }
        }
    }
    radiance
}
