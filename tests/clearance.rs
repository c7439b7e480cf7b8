//! The clearance of a surface point (`hexray::clearance`), which bounds vcm's merge radius at a
//! camera vertex: the BVH query finds exactly what a brute-force scan over every primitive
//! finds, and its nearest point on a triangle is the nearest.

use crate::common::load;
use glam::Vec3;
use hexray::clearance::{clearance, closest_point_on_triangle, coplanar, COPLANAR_OFFSET};
use hexray::flat::{FlatScene, Triangle, PRIM_SPHERE_BIT};
use hexray::merging::scene_radius;

/// A fixed stream of uniform numbers in [0, 1) (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32) / (1u64 << 24) as f32
    }
}

/// A uniform point on primitive `prim` (its id as `FlatScene::prims` holds it).
fn point_on(scene: &FlatScene, prim: u32, rng: &mut Rng) -> Vec3 {
    if prim & PRIM_SPHERE_BIT != 0 {
        let s = &scene.spheres[(prim & !PRIM_SPHERE_BIT) as usize];
        let z = 1.0 - 2.0 * rng.next();
        let phi = std::f32::consts::TAU * rng.next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::from(s.center) + s.radius * Vec3::new(r * phi.cos(), r * phi.sin(), z)
    } else {
        let t = &scene.triangles[prim as usize];
        let (mut u, mut v) = (rng.next(), rng.next());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        Vec3::from(t.v0)
            + u * (Vec3::from(t.v1) - Vec3::from(t.v0))
            + v * (Vec3::from(t.v2) - Vec3::from(t.v0))
    }
}

/// The clearance by definition: the least distance from `p` to every primitive but `prim` and
/// those in its plane, at most `bound`; `with_spheres` false leaves the spheres out (a planted
/// error).
fn brute_force(scene: &FlatScene, p: Vec3, prim: u32, bound: f32, with_spheres: bool) -> f32 {
    let own = (prim & PRIM_SPHERE_BIT == 0).then(|| &scene.triangles[prim as usize]);
    let tolerance = COPLANAR_OFFSET * (p.abs().max_element() + bound).max(1.0);
    let mut best2 = bound * bound;
    for (i, t) in scene.triangles.iter().enumerate() {
        if i as u32 == prim || own.is_some_and(|o| coplanar(o, t, tolerance)) {
            continue;
        }
        best2 = best2.min((closest_point_on_triangle(p, t) - p).length_squared());
    }
    for (i, s) in scene.spheres.iter().enumerate() {
        if !with_spheres || i as u32 | PRIM_SPHERE_BIT == prim {
            continue;
        }
        let d = (p - Vec3::from(s.center)).length() - s.radius;
        best2 = best2.min(d * d);
    }
    best2.sqrt()
}

/// Random points on random primitives of `rel`, with bounds up to 5 % of the scene radius:
/// how many of them the BVH query and the brute force (`with_spheres` as given) disagree on,
/// out of `n`, and how many have a clearance below their bound (the query's work).
fn disagreements(rel: &str, n: usize, with_spheres: bool) -> (usize, usize) {
    let (_, flat) = load(rel);
    let prims = flat.triangles.len() + flat.spheres.len();
    let radius = scene_radius(&flat);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut differ, mut near) = (0, 0);
    for _ in 0..n {
        let k = ((rng.next() * prims as f32) as usize).min(prims - 1);
        let prim = if k < flat.triangles.len() {
            k as u32
        } else {
            (k - flat.triangles.len()) as u32 | PRIM_SPHERE_BIT
        };
        let p = point_on(&flat, prim, &mut rng);
        let bound = 0.05 * radius * rng.next();
        let got = clearance(&flat, p, prim, bound);
        differ += usize::from(got != brute_force(&flat, p, prim, bound, with_spheres));
        near += usize::from(got < bound);
    }
    (differ, near)
}

/// The query prunes the tree by each box's distance and keeps the least distance it meets, so
/// it must equal the scan over every primitive exactly (the same f32 distances, and the
/// minimum does not depend on their order). 4000 points on each reference room, a quarter to
/// half of them nearer another surface than their bound.
#[test]
fn the_clearance_is_the_least_distance_to_any_surface_off_the_points_plane() {
    for rel in [
        "scenes/tncg15_room.json",
        "scenes/glass_room.json",
        "scenes/cornell_box.json",
    ] {
        let (differ, near) = disagreements(rel, 4000, true);
        eprintln!("{rel}: {near} of 4000 points nearer another surface than their bound");
        assert_eq!(differ, 0, "{rel}: {differ} of 4000 points differ");
        assert!(
            near > 100,
            "{rel}: only {near} points are near another surface"
        );
    }
}

/// The check has power: a scan that leaves the spheres out (a clearance blind to the mirror
/// sphere on tncg15_room's floor) disagrees with the query on points near the sphere.
#[test]
fn the_clearance_check_rejects_a_scan_blind_to_spheres() {
    let (differ, _) = disagreements("scenes/tncg15_room.json", 4000, false);
    assert!(differ > 10, "only {differ} of 4000 points differ");
}

/// Ericson's closest point lies on the triangle and no point of a fine barycentric lattice on
/// it is nearer (up to the lattice's spacing and f32 rounding), for random triangles and
/// points around them.
#[test]
fn the_closest_point_on_a_triangle_is_the_nearest() {
    let mut rng = Rng(42);
    let mut v = || Vec3::new(rng.next(), rng.next(), rng.next()) * 2.0 - 1.0;
    for _ in 0..300 {
        let t = Triangle::new(v().into(), v().into(), v().into(), 0);
        let p = 2.0 * v();
        let q = closest_point_on_triangle(p, &t);
        let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
        // On the triangle: within the plane, and its barycentrics non-negative.
        let n = (b - a).cross(c - a);
        let area = n.length_squared();
        let bary = |x: Vec3, y: Vec3| (x - q).cross(y - q).dot(n) / area;
        let (wa, wb, wc) = (bary(b, c), bary(c, a), bary(a, b));
        assert!(wa.min(wb).min(wc) > -1e-4, "{wa} {wb} {wc}");
        assert!((wa + wb + wc - 1.0).abs() < 1e-3);
        let d = (q - p).length();
        let steps = 64;
        let mut best = f32::INFINITY;
        for i in 0..=steps {
            for j in 0..=steps - i {
                let (u, w) = (i as f32 / steps as f32, j as f32 / steps as f32);
                best = best.min((a + u * (b - a) + w * (c - a) - p).length());
            }
        }
        let spacing = (b - a).length().max((c - a).length()) / steps as f32;
        assert!(d <= best + 1e-5, "closest {d}, lattice {best}");
        assert!(best <= d + spacing, "closest {d}, lattice {best}");
    }
}
