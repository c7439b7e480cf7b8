//! Spawned rays never hit the surface they leave (pbrt-v4's `Triangle.Reintersect` and
//! `Sphere.Reintersect` tests): for random primitives with coordinates up to 1e5 in magnitude,
//! a hit point is found by intersecting a ray, then 1000 rays are spawned from it in uniformly
//! random directions. Leaving a triangle, a ray must not hit it again (a plane can only be met
//! once); leaving a sphere outward it must miss, inward it must find the far side, not itself.
//! Spheres are at least 1e-5 of their distance from the origin in radius (see below).
//! Exact counts, no statistics: a single self-hit fails.

use glam::{DVec3, Vec3};
use hexray::layout::{Sphere, Triangle};
use hexray::math::geometry::{
    intersect_sphere, intersect_triangle, offset_ray_origin, sphere_point, triangle_normal,
    triangle_point, Ray,
};
use hexray::math::sampling::Sampler;

/// A coordinate of random sign and magnitude 10^[-2, 5): mixes tiny and huge values, as pbrt's
/// test does, so that the error bounds are exercised at every scale.
fn coord(u: f32, v: f32) -> f32 {
    let m = 10f32.powf(-2.0 + 7.0 * u);
    if v < 0.5 {
        -m
    } else {
        m
    }
}

fn uniform_sphere(u: [f32; 4]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The offset is tiny: a few ulps of the coordinates, not a fraction of the scene (the 2020
/// report moved points 4 % along the normal; Mitsuba 3 moves them (1 + max|p|) · 9e-5).
fn assert_offset_is_tiny(o: Vec3, p: Vec3) {
    let scale = 1.0 + p.abs().max_element() as f64;
    let d = (o.as_dvec3() - p.as_dvec3()).length();
    assert!(d <= 1e-5 * scale, "offset {d} at |p| = {scale}");
}

/// How a spawned ray's origin is chosen from the hit point, its error bound and its normal.
type Spawn = fn(Vec3, Vec3, Vec3, Vec3) -> Vec3;

/// The hit point itself, with no offset: the planted error the tests must catch.
fn no_offset(p: Vec3, _p_err: Vec3, _n: Vec3, _w: Vec3) -> Vec3 {
    p
}

#[test]
fn rays_leaving_a_triangle_never_hit_it_again() {
    assert_eq!(triangle_self_hits(offset_ray_origin), 0);
}

#[test]
fn rays_leaving_a_sphere_never_hit_it_at_the_start() {
    assert_eq!(sphere_self_hits(offset_ray_origin), 0);
}

/// Power: without the offset, the same tests find self-hits.
#[test]
fn reintersect_tests_catch_rays_spawned_without_offset() {
    let (t, s) = (triangle_self_hits(no_offset), sphere_self_hits(no_offset));
    eprintln!("without offset: {t} triangle and {s} sphere self-hits in 10^6 rays each");
    assert!(t > 0 && s > 0);
}

/// Spawns 1000 rays from a hit on each of 1000 random triangles; returns the self-hits.
fn triangle_self_hits(spawn: Spawn) -> usize {
    let (mut hits, mut spawned, mut self_hits) = (0, 0, 0);
    for i in 0..1000u32 {
        let s = Sampler::new(77, i, 0);
        let (a, b, c) = (s.draw4(0), s.draw4(1), s.draw4(2));
        let (d, e) = (s.draw4(3), s.draw4(4));
        let tri = Triangle::new(
            [coord(a[0], a[1]), coord(a[2], a[3]), coord(b[0], b[1])],
            [coord(b[2], b[3]), coord(c[0], c[1]), coord(c[2], c[3])],
            [coord(d[0], d[1]), coord(d[2], d[3]), coord(e[0], e[1])],
            0,
        );
        let n = triangle_normal(&tri);
        if !n.is_finite() {
            continue;
        }
        // A ray toward a random point of the triangle, from a random origin.
        let f = s.draw4(5);
        let (b1, b2) = if f[0] + f[1] > 1.0 {
            (1.0 - f[0], 1.0 - f[1])
        } else {
            (f[0], f[1])
        };
        let target = DVec3::from(tri.v0.map(f64::from)) * (1.0 - b1 - b2) as f64
            + DVec3::from(tri.v1.map(f64::from)) * b1 as f64
            + DVec3::from(tri.v2.map(f64::from)) * b2 as f64;
        let g = s.draw4(6);
        let o = Vec3::new(coord(g[0], g[1]), coord(g[2], g[3]), coord(f[2], f[3]));
        let ray = Ray {
            o,
            d: (target - o.as_dvec3()).normalize().as_vec3(),
        };
        let Some(h) = intersect_triangle(&ray, &tri) else {
            continue;
        };
        hits += 1;
        let (p, p_err) = triangle_point(&tri, h.b1, h.b2);
        for j in 0..1000u32 {
            let w = uniform_sphere(Sampler::new(78, i, j).draw4(0));
            let origin = spawn(p, p_err, n, w);
            assert_offset_is_tiny(origin, p);
            let out = Ray { o: origin, d: w };
            spawned += 1;
            if intersect_triangle(&out, &tri).is_some() {
                self_hits += 1;
            }
        }
    }
    // The test must have done its work: most random rays aimed at a triangle hit it.
    assert!(hits > 900, "only {hits} triangles hit");
    eprintln!("triangles: {spawned} spawned rays, {self_hits} self-hits");
    self_hits
}

/// Spawns 1000 rays from a hit on each of 1000 random spheres; returns the rays that hit their
/// sphere at the start (outward rays that hit at all, inward rays that stop short of the chord).
fn sphere_self_hits(spawn: Spawn) -> usize {
    let (mut spawned, mut self_hits) = (0, 0);
    for i in 0..1000u32 {
        let s = Sampler::new(79, i, 0);
        let (a, b) = (s.draw4(0), s.draw4(1));
        let center = Vec3::new(coord(a[0], a[1]), coord(a[2], a[3]), coord(b[0], b[1]));
        // Radii from 1e-2 to 1e4, but at least 1e-5 of the centre's largest coordinate: f32
        // spaces points 6e-8 |c| apart, so a sphere of radius 1e-6 |c| is 15 ulps across and
        // its error box (2.4e-7 |c|) is as big as the sphere; such spheres are out of reach of
        // world-space f32 geometry (pbrt keeps spheres in object space for this reason).
        let radius = 10f32
            .powf(-2.0 + 6.0 * b[2])
            .max(1e-5 * center.abs().max_element());
        let sphere = Sphere {
            center: center.into(),
            radius,
            ..Default::default()
        };
        // From a random point outside, toward a point near the centre.
        let dir_out = uniform_sphere(s.draw4(2));
        let dist = radius * (1.0 + 10f32.powf(-3.0 + 5.0 * b[3]));
        let o = center + dir_out * dist;
        let aim = center + uniform_sphere(s.draw4(3)) * (0.5 * radius);
        let ray = Ray {
            o,
            d: (aim - o).normalize(),
        };
        let h = intersect_sphere(&ray, &sphere)
            .unwrap_or_else(|| panic!("sphere {i}: the aimed ray missed"));
        let (p, p_err, n) = sphere_point(&ray, &sphere, h.t);
        for j in 0..1000u32 {
            let w = uniform_sphere(Sampler::new(80, i, j).draw4(0));
            let origin = spawn(p, p_err, n, w);
            assert_offset_is_tiny(origin, p);
            let out = Ray { o: origin, d: w };
            spawned += 1;
            let cos = w.dot(n);
            let again = intersect_sphere(&out, &sphere);
            if cos > 0.0 {
                self_hits += again.is_some() as usize;
            } else if cos < -1e-2 {
                // Inward: the far side is a chord 2 r |cos| away.
                let chord = 2.0 * radius * -cos;
                self_hits += (again.map_or(0.0, |g| g.t) <= 0.5 * chord) as usize;
            }
        }
    }
    eprintln!("spheres: {spawned} spawned rays, {self_hits} self-hits");
    self_hits
}
