//! Planar mirrors, and next-event estimation through them.
//!
//! A diffuse wall lit by way of a plane mirror sees the light's mirror image: a second light,
//! as small and as bright as the first. Next-event estimation cannot aim at it (the light point
//! it samples is the real one), BSDF sampling meets it as rarely as it meets the light itself,
//! and a light subpath reaches the wall by way of the mirror only as one of its vertices. So on
//! tncg15_room, whose mirror wall doubles the room's light, that light is the noisiest part of
//! the walls' (docs/performance.md). Reflecting the light point of next-event estimation in the
//! mirror's plane gives a point y' of the same area density, and the path x → m → y through
//! the mirror point m on the segment x y' is a next-event path of its own: its geometry term is
//! that of x and y', |x − y'| = |x − m| + |m − y|, and it carries the mirror's reflectance.
//!
//! **Which strategy takes such a path.** The bidirectional methods weigh every strategy that
//! makes a path by MIS. Here the weights are a partition rather than a heuristic: a path whose
//! light end is a light point, a planar mirror and a diffuse vertex ([`starts_by_a_mirror`])
//! is taken by next-event estimation through the mirror alone (weight 1), and by no other
//! strategy (weight 0: the camera subpath that meets the light from that mirror, and the light
//! subpath's vertices from the diffuse one on, which the light pass does not store or splat).
//! Any partition of the paths among the strategies is a valid MIS weighting (Veach's thesis,
//! eq. 9.3: the weights of a path sum to 1), so the estimate stays unbiased; and for a small
//! light seen from a diffuse vertex, next-event estimation is the strategy the balance heuristic
//! gives nearly all the weight to anyway (Veach's thesis, fig. 10.3). Paths without that light
//! end keep their weights over the other strategies, unchanged. Path tracing (the unbiased
//! reference), light tracing and SPPM do not take this strategy.
//!
//! A planar mirror is the set of the scene's mirror triangles in one plane, found here once
//! ([`find`]); a scene keeps the [`MAX_PLANAR_MIRRORS`] of largest area. Mirror spheres are not
//! planar and stay as they were. `shaders/planar_mirror.wgsl` is this module again.

use crate::flat::{
    triangle_area, FlatScene, Material, PlanarMirror, Triangle, KIND_MIRROR, PRIM_SPHERE_BIT,
};
use glam::{DVec3, Vec3};

/// The most planar mirrors a scene keeps (the largest by area): each costs a closest-hit ray
/// per diffuse vertex whose mirror point falls in its bounds.
pub const MAX_PLANAR_MIRRORS: u32 = 4;

/// How far a mirror triangle's normal may turn from its plane's: |n · n_plane| ≥ 1 − this.
pub const PARALLEL: f32 = 1e-6;

/// Marks a primitive on no planar mirror (the shader's `planar_mirror_of`; `None` here).
pub const NO_PLANAR_MIRROR: u32 = u32::MAX;

/// The planar mirrors of a scene: its mirror triangles grouped by plane (normal parallel, every
/// vertex within the plane's tolerance, the same material), the largest `MAX_PLANAR_MIRRORS`
/// by area, largest first.
pub fn find(triangles: &[Triangle], materials: &[Material]) -> Vec<PlanarMirror> {
    // Coordinates' magnitude sets how far from its plane a vertex given in f32 may lie.
    let extent = triangles
        .iter()
        .flat_map(|t| [t.v0, t.v1, t.v2])
        .flatten()
        .fold(1.0f64, |m, c| m.max(f64::from(c).abs()));
    let tolerance = 1e-5 * extent;
    // (mirror, area) of each plane found so far.
    let mut planes: Vec<(PlanarMirror, f64)> = Vec::new();
    for t in triangles {
        let m = &materials[t.material as usize];
        let area = f64::from(triangle_area(t));
        if m.kind != KIND_MIRROR || area <= 0.0 || !area.is_finite() {
            continue;
        }
        let index = planes
            .iter()
            .position(|(p, _)| p.material == t.material && in_plane(p, t));
        let (lo, hi) = triangle_bounds(t);
        match index {
            Some(k) => {
                let (p, a) = &mut planes[k];
                p.lo = Vec3::from(p.lo).min(lo).into();
                p.hi = Vec3::from(p.hi).max(hi).into();
                *a += area;
            }
            None => {
                let n = DVec3::from(t.n.map(f64::from));
                let d = n.dot(DVec3::from(t.v0.map(f64::from)));
                planes.push((
                    PlanarMirror {
                        n: t.n,
                        d: d as f32,
                        lo: lo.into(),
                        tolerance: tolerance as f32,
                        hi: hi.into(),
                        material: t.material,
                    },
                    area,
                ));
            }
        }
    }
    // Largest first; a stable sort keeps the file's order among equal areas.
    planes.sort_by(|a, b| b.1.total_cmp(&a.1));
    planes
        .into_iter()
        .take(MAX_PLANAR_MIRRORS as usize)
        .map(|(p, _)| p)
        .collect()
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

/// The planar mirror that primitive `prim` (a `SurfaceHit::prim`) belongs to, if any: a
/// triangle of the mirror's material in its plane.
#[inline]
pub fn planar_mirror_of(scene: &FlatScene, prim: u32) -> Option<usize> {
    if scene.planar_mirrors.is_empty() || prim & PRIM_SPHERE_BIT != 0 {
        return None;
    }
    let t = &scene.triangles[prim as usize];
    scene
        .planar_mirrors
        .iter()
        .position(|p| p.material == t.material && in_plane(p, t))
}

/// Whether a path whose light end is the light point, then the vertex of primitive
/// `first_prim`, then a vertex that `second_diffuse` says is diffuse, is one that next-event
/// estimation through a planar mirror takes (and no other strategy).
#[inline]
pub fn starts_by_a_mirror(scene: &FlatScene, first_prim: u32, second_diffuse: bool) -> bool {
    second_diffuse && planar_mirror_of(scene, first_prim).is_some()
}

/// The light point `y` (normal `n_y`) seen from `x` by way of `mirror`: the image y' of `y`
/// in the mirror's plane, the image's normal, and the point m where the segment x y' crosses
/// the plane; `None` where `x` and `y` are not strictly on the same side of the plane or m
/// falls outside the mirror's bounds. Whether m is on the mirror and the segment x m is clear
/// is for a closest-hit ray to say.
#[inline]
pub fn image(mirror: &PlanarMirror, x: Vec3, y: Vec3, n_y: Vec3) -> Option<(Vec3, Vec3, Vec3)> {
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
    let slack = Vec3::splat(mirror.tolerance);
    let inside = m.cmpge(Vec3::from(mirror.lo) - slack).all()
        && m.cmple(Vec3::from(mirror.hi) + slack).all();
    inside.then_some((y_image, n_image, m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flat::KIND_DIFFUSE;

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
        let found = find(&wall, &mirror_material());
        assert_eq!(found.len(), 2);
        assert_eq!(found[0].hi, [10.0, -6.0, 5.0]);
        assert_eq!(found[0].lo, [0.0, -6.0, -5.0]);
        assert!(in_plane(&found[0], &wall[1]));
        assert!(!in_plane(&found[0], &wall[3]));
    }

    #[test]
    fn the_image_path_has_the_length_of_the_reflected_one() {
        let t = Triangle::new([-5.0, 0.0, -5.0], [5.0, 0.0, -5.0], [5.0, 0.0, 5.0], 0);
        let mirror = find(&[t], &mirror_material())[0];
        let (x, y) = (Vec3::new(0.0, 2.0, 0.0), Vec3::new(1.0, 3.0, 1.0));
        let (y_image, n_image, m) = image(&mirror, x, y, Vec3::Y).unwrap();
        assert!((m.y).abs() < 1e-6);
        let folded = (m - x).length() + (y - m).length();
        assert!(((y_image - x).length() - folded).abs() < 1e-5);
        assert_eq!(n_image, -Vec3::Y);
        // Opposite sides: no image.
        assert!(image(&mirror, x, Vec3::new(0.0, -1.0, 0.0), Vec3::Y).is_none());
    }
}
