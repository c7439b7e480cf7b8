//! Planar mirrors, and next-event estimation through them.
//!
//! A diffuse wall lit by way of a plane mirror sees the light's mirror image: a second light,
//! as small and as bright as the first. Next-event estimation cannot aim at it (the light point
//! it samples is the real one), BSDF sampling meets it as rarely as it meets the light itself,
//! and a light subpath reaches the wall by way of the mirror only with the few of its
//! directions that meet the mirror. On tncg15_room, whose mirror wall doubles the room's light,
//! that light is noisy for every method (docs/journal/2026-11-25_mirror_share.md). Reflecting the light point y of
//! next-event estimation in the mirror's plane gives a point y' of the same area density, and
//! the path x → m → y through the point m where the segment x y' crosses the mirror is a
//! next-event path of its own: its geometry term is that of x and y' (|x − y'| = |x − m| +
//! |m − y|, and the cosine at y' is the cosine at y toward m), and it carries the mirror's
//! reflectance.
//!
//! **Which strategy takes such a path.** The bidirectional methods weigh the strategies that
//! make a path by MIS. Here the weights are a partition rather than a heuristic: a path whose
//! light end is a light point, a planar mirror and a diffuse vertex ([`starts_by_a_mirror`])
//! is taken by next-event estimation through the mirror alone (weight 1), and by no other
//! strategy (weight 0): not by the camera subpath that meets the light in that mirror from a
//! diffuse vertex, and not by the light subpath's vertices from that diffuse vertex on, which
//! the light pass does not store or splat. MIS needs only that a path's weights over the
//! strategies that can make it sum to 1 (Veach's thesis, section 9.2), which a partition
//! satisfies, so the estimate stays unbiased. For a small light seen from a diffuse vertex,
//! next-event estimation is the strategy the power heuristic gives most of the weight anyway;
//! where the light's image is close to the vertex, the BSDF sampling it replaces would have
//! done better. Paths without that light end keep their weights over the other strategies.
//! BDPT takes this strategy ([`takes_mirror_light`]); VCM that merges, path tracing (the
//! unbiased reference), light tracing and SPPM do not.
//!
//! A planar mirror is the set of the scene's mirror triangles of one material in one plane,
//! found once ([`find`]), which also marks each triangle with its plane
//! (`Triangle::planar_mirror`). A scene keeps the [`MAX_PLANAR_MIRRORS`] of largest area.
//! Mirror spheres are not planar and stay as they were. `shaders/planar_mirror.wgsl` is this
//! module again.

use crate::layout::{
    triangle_area, FlatScene, Material, PlanarMirror, Triangle, KIND_MIRROR, PRIM_SPHERE_BIT,
};
pub use crate::layout::{MAX_PLANAR_MIRRORS, NO_PLANAR_MIRROR};
use glam::{DVec3, Vec3};

/// The most planes [`find`] tells apart: past them, a mirror triangle in a plane not yet seen
/// is no planar mirror's (a tessellated curved mirror, whose facets are each a plane of their
/// own, would otherwise cost time quadratic in its facets).
pub const MAX_CANDIDATE_PLANES: usize = 64;

/// How far a mirror triangle's normal may turn from its plane's: |n · n_plane| ≥ 1 − this.
pub const PARALLEL: f32 = 1e-6;

/// The slack of [`image`]'s bounds test beyond the plane's tolerance, per unit of the
/// magnitudes m is computed from (|x| and |y' − x|): 16 f32 epsilons, 2^-19. The closest-hit
/// ray decides whether m is on the mirror; this test only spares rays that cannot meet it, so
/// it must never turn away a mirror point that rounding moved off a bounds box that is flat
/// along the mirror's normal.
pub const BOUNDS_SLACK: f32 = 1.0 / 524_288.0;

/// How far from its plane a vertex may lie, in units of f32's epsilon times the largest
/// coordinate of the scene's mirror triangles: a vertex given in f64 and rounded to f32 moves by
/// half an ulp of its coordinates.
const TOLERANCE_EPSILONS: f32 = 32.0;

/// The planar mirrors of a scene: its mirror triangles grouped by plane (normal parallel, every
/// vertex within the plane's tolerance, the same material), the largest `MAX_PLANAR_MIRRORS`
/// by area, largest first; sets each triangle's `planar_mirror` to its plane's index (or
/// `NO_PLANAR_MIRROR`), which is what the integrators read.
pub fn find(triangles: &mut [Triangle], materials: &[Material]) -> Vec<PlanarMirror> {
    let is_mirror = |t: &Triangle| {
        let area = triangle_area(t);
        materials[t.material as usize].kind == KIND_MIRROR && area > 0.0 && area.is_finite()
    };
    let extent = triangles
        .iter()
        .filter(|t| is_mirror(t))
        .flat_map(|t| [t.v0, t.v1, t.v2])
        .flatten()
        .fold(0.0f32, |m, c| m.max(c.abs()));
    let tolerance = TOLERANCE_EPSILONS * f32::EPSILON * extent.max(f32::MIN_POSITIVE);
    // (mirror, area) of each plane found, and the plane of each triangle.
    let mut planes: Vec<(PlanarMirror, f64)> = Vec::new();
    let mut plane_of = vec![NO_PLANAR_MIRROR; triangles.len()];
    for (t, plane) in triangles.iter().zip(plane_of.iter_mut()) {
        if !is_mirror(t) {
            continue;
        }
        let area = f64::from(triangle_area(t));
        let (lo, hi) = triangle_bounds(t);
        let found = planes
            .iter()
            .position(|(p, _)| p.material == t.material && in_plane(p, t));
        if let Some(k) = found {
            let (p, a) = &mut planes[k];
            p.lo = Vec3::from(p.lo).min(lo).into();
            p.hi = Vec3::from(p.hi).max(hi).into();
            *a += area;
            *plane = k as u32;
        } else if planes.len() < MAX_CANDIDATE_PLANES {
            let n = DVec3::from(t.n.map(f64::from));
            let d = n.dot(DVec3::from(t.v0.map(f64::from)));
            let mirror = PlanarMirror {
                n: t.n,
                d: d as f32,
                lo: lo.into(),
                tolerance,
                hi: hi.into(),
                material: t.material,
            };
            // A triangle defines its plane only if it lies in it within the tolerance (its
            // normal, in f32, may not).
            if in_plane(&mirror, t) {
                *plane = planes.len() as u32;
                planes.push((mirror, area));
            }
        }
    }
    // Largest first; a stable sort keeps the file's order among equal areas.
    let mut order: Vec<usize> = (0..planes.len()).collect();
    order.sort_by(|&a, &b| planes[b].1.total_cmp(&planes[a].1));
    order.truncate(MAX_PLANAR_MIRRORS as usize);
    let mut index = vec![NO_PLANAR_MIRROR; planes.len()];
    for (i, &k) in order.iter().enumerate() {
        index[k] = i as u32;
    }
    for (t, plane) in triangles.iter_mut().zip(plane_of) {
        t.planar_mirror = if plane == NO_PLANAR_MIRROR {
            NO_PLANAR_MIRROR
        } else {
            index[plane as usize]
        };
    }
    order.iter().map(|&k| planes[k].0).collect()
}

/// Whether triangle `t` lies in `plane`: its normal parallel to the plane's and each vertex
/// within the plane's tolerance of it.
pub fn in_plane(plane: &PlanarMirror, t: &Triangle) -> bool {
    let n = Vec3::from(plane.n);
    n.dot(Vec3::from(t.n)).abs() >= 1.0 - PARALLEL
        && [t.v0, t.v1, t.v2]
            .iter()
            .all(|v| (n.dot(Vec3::from(*v)) - plane.d).abs() <= plane.tolerance)
}

fn triangle_bounds(t: &Triangle) -> (Vec3, Vec3) {
    let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
    (a.min(b).min(c), a.max(b).max(c))
}

/// Whether a method takes next-event estimation through planar mirrors: one that `connects`
/// (BDPT's strategies) and does not `merge`, in a scene with planar mirrors. So BDPT does, and
/// vcm with the radius 0, which is BDPT. VCM that merges does not: its merges at the diffuse
/// vertex after the mirror already take that light with little noise, and on 2 cores the
/// strategy's closest-hit rays cost about what its lower variance saves (docs/journal/2026-11-26_planar_mirrors.md);
/// nor do path tracing, light tracing and SPPM.
#[inline]
pub fn takes_mirror_light(connects: bool, merges: bool, scene: &FlatScene) -> bool {
    connects && !merges && !scene.planar_mirrors.is_empty()
}

/// The planar mirror that primitive `prim` (a `SurfaceHit::prim`) is part of, if any.
#[inline]
pub fn planar_mirror_of(scene: &FlatScene, prim: u32) -> Option<usize> {
    if scene.planar_mirrors.is_empty() || prim & PRIM_SPHERE_BIT != 0 {
        return None;
    }
    let i = scene.triangles[prim as usize].planar_mirror;
    (i != NO_PLANAR_MIRROR).then_some(i as usize)
}

/// Whether a path whose light end is the light point, then the vertex of primitive
/// `first_prim`, then a vertex that `second_diffuse` says is diffuse, is one that next-event
/// estimation through a planar mirror takes (and no other strategy).
#[inline]
pub fn starts_by_a_mirror(scene: &FlatScene, first_prim: u32, second_diffuse: bool) -> bool {
    second_diffuse && planar_mirror_of(scene, first_prim).is_some()
}

/// The light point `y` (normal `n_y`) seen from `x` by way of `mirror`: the image y' of `y`
/// in the mirror's plane and the image's normal; `None` where `x` and `y` are not strictly on
/// the same side of the plane or the point m where the segment x y' crosses the plane falls
/// outside the mirror's bounds. Whether m is on the mirror and the segment x m is clear is for
/// a closest-hit ray to say.
#[inline]
pub fn image(mirror: &PlanarMirror, x: Vec3, y: Vec3, n_y: Vec3) -> Option<(Vec3, Vec3)> {
    let n = Vec3::from(mirror.n);
    // Signed distances to the plane.
    let sx = n.dot(x) - mirror.d;
    let sy = n.dot(y) - mirror.d;
    if sx * sy <= 0.0 {
        return None;
    }
    let y_image = y - 2.0 * sy * n;
    let n_image = n_y - 2.0 * n.dot(n_y) * n;
    // The segment x y' crosses the plane where the signed distance goes from sx to −sy.
    let m = x + (y_image - x) * (sx / (sx + sy));
    let scale = x.abs().max_element() + (y_image - x).abs().max_element();
    let slack = Vec3::splat(mirror.tolerance + BOUNDS_SLACK * scale);
    let inside = m.cmpge(Vec3::from(mirror.lo) - slack).all()
        && m.cmple(Vec3::from(mirror.hi) + slack).all();
    inside.then_some((y_image, n_image))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::KIND_DIFFUSE;

    fn mirror_material() -> Vec<Material> {
        vec![
            Material {
                color: [1.0; 3],
                kind: KIND_MIRROR,
                ..Default::default()
            },
            Material {
                color: [0.5; 3],
                kind: KIND_DIFFUSE,
                ..Default::default()
            },
        ]
    }

    #[test]
    fn coplanar_mirror_triangles_are_one_planar_mirror_and_others_are_not() {
        let wall = [
            Triangle::new([0.0, -6.0, -5.0], [10.0, -6.0, -5.0], [10.0, -6.0, 5.0], 0),
            Triangle::new([0.0, -6.0, -5.0], [10.0, -6.0, 5.0], [0.0, -6.0, 5.0], 0),
            // Diffuse, in the same plane: not a mirror.
            Triangle::new([10.0, -6.0, -5.0], [12.0, -6.0, -5.0], [12.0, -6.0, 5.0], 1),
            // A mirror in another plane.
            Triangle::new([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0),
        ];
        let mut triangles = wall;
        let found = find(&mut triangles, &mirror_material());
        assert_eq!(found.len(), 2);
        assert_eq!(found[0].hi, [10.0, -6.0, 5.0]);
        assert_eq!(found[0].lo, [0.0, -6.0, -5.0]);
        assert!(in_plane(&found[0], &wall[1]));
        assert!(!in_plane(&found[0], &wall[3]));
        let planes: Vec<u32> = triangles.iter().map(|t| t.planar_mirror).collect();
        assert_eq!(planes, [0, 0, NO_PLANAR_MIRROR, 1]);
    }

    #[test]
    fn a_scene_keeps_the_largest_planar_mirrors_and_tells_a_bounded_number_of_planes_apart() {
        // Mirror triangles each in a plane of its own (z = k), the k-th of area k + 1.
        let triangles: Vec<Triangle> = (0..MAX_CANDIDATE_PLANES + 6)
            .map(|k| {
                let (z, s) = (k as f32, (2.0 * (k as f32 + 1.0)).sqrt());
                Triangle::new([0.0, 0.0, z], [s, 0.0, z], [0.0, s, z], 0)
            })
            .collect();
        let mut marked = triangles.clone();
        let found = find(&mut marked, &mirror_material());
        // The largest of the planes told apart (the first MAX_CANDIDATE_PLANES), largest first.
        let d: Vec<f32> = found.iter().map(|p| p.d * p.n[2]).collect();
        let last = (MAX_CANDIDATE_PLANES - 1) as f32;
        assert_eq!(d, [last, last - 1.0, last - 2.0, last - 3.0]);
        for (k, t) in marked.iter().enumerate() {
            let expected = match (MAX_CANDIDATE_PLANES - 1).checked_sub(k) {
                Some(i) if i < MAX_PLANAR_MIRRORS as usize => i as u32,
                _ => NO_PLANAR_MIRROR,
            };
            assert_eq!(t.planar_mirror, expected, "triangle {k}");
        }
    }

    #[test]
    fn a_mirror_small_beside_the_scenes_coordinates_keeps_its_images() {
        // A mirror 0.1 wide at the origin (plane y = 0, tolerance ~4e-7), seen from points
        // tens of units away by way of mirror points well inside it: rounding moves the
        // computed m off the plane by about an ulp of those coordinates (~2e-6), which the
        // bounds test must allow.
        let t = Triangle::new([0.0, 0.0, 0.0], [0.0, 0.0, 0.1], [0.1, 0.0, 0.1], 0);
        let u = Triangle::new([0.0, 0.0, 0.0], [0.1, 0.0, 0.1], [0.1, 0.0, 0.0], 0);
        let mut triangles = [t, u];
        let mirror = find(&mut triangles, &mirror_material())[0];
        let mut state = 12345u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / 16_777_216.0
        };
        let mut kept = 0;
        for _ in 0..10_000 {
            let m = Vec3::new(0.01 + 0.08 * next(), 0.0, 0.01 + 0.08 * next());
            let x = Vec3::new(
                40.0 * next() - 20.0,
                5.0 + 30.0 * next(),
                40.0 * next() - 20.0,
            );
            // The light point on the reflected ray from m.
            let d = (m - x).normalize();
            let reflected = Vec3::new(d.x, -d.y, d.z);
            let y = m + reflected * (5.0 + 30.0 * next());
            kept += usize::from(image(&mirror, x, y, -reflected).is_some());
        }
        assert_eq!(kept, 10_000);
    }

    #[test]
    fn the_image_path_has_the_length_of_the_reflected_one() {
        let t = Triangle::new([-5.0, 0.0, -5.0], [5.0, 0.0, -5.0], [5.0, 0.0, 5.0], 0);
        let mirror = find(&mut [t], &mirror_material())[0];
        let (x, y) = (Vec3::new(0.0, 2.0, 0.0), Vec3::new(1.0, 3.0, 1.0));
        let (y_image, n_image) = image(&mirror, x, y, Vec3::Y).unwrap();
        // The mirror point: where x y' meets the plane y = 0.
        let m = x + (y_image - x) * (x.y / (x.y - y_image.y));
        assert!((m.y).abs() < 1e-6);
        let folded = (m - x).length() + (y - m).length();
        assert!(((y_image - x).length() - folded).abs() < 1e-5);
        assert_eq!(n_image, -Vec3::Y);
        // Opposite sides: no image.
        assert!(image(&mirror, x, Vec3::new(0.0, -1.0, 0.0), Vec3::Y).is_none());
    }
}
