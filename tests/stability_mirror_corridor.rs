//! A mirror corridor: two parallel mirrors of reflectance 1 (x = 0 and x = 1) with a one-sided
//! emitter panel between them (`scenes/stability/mirror_corridor.json`). Paths keep unit
//! throughput at every bounce, and rays that miss the light bounce thousands of times before they
//! leave the mirrors, so only Russian roulette ends them; a depth cap or a dim mirror loses light.
//!
//! The exact image is a finite series, computed here in f64 from the scene's geometry alone.
//! Unfold the reflections: a camera ray from (0.5, 0, 0) with slopes (a, b) = (dy/dx, dz/dx)
//! crosses the images of any plane x = p at unfolded distances D (p − 0.5 + 2m and 1.5 − p + 2m,
//! m = 0, 1, ...), there at (y, z) = (a D, b D). It ends at the first crossing whose point lies
//! in the emitter panel (seeing Le when it crosses going −x, toward the panel's front, and its
//! black back otherwise) or in the black square on the axis. In slope space a rectangle
//! [y0, y1] x [z0, z1] at distance D is the rectangle [y0/D, y1/D] x [z0/D, z1/D], and the camera
//! maps pixels to slope rectangles linearly (box filter), so each pixel's expectation is Le times
//! the area of its slope rectangle whose first event is a front crossing, over its area: exact
//! rectangle clipping on the grid of all event edges inside the pixel. The series is finite:
//! from the crossing where the panel's slope rectangle lies inside the black square's (k = 50)
//! on, no ray can reach the light.
//!
//! Statistic: 8x8 blocks. A block whose exact value is 0 (the black square, the panel's back,
//! directions that never meet the panel) must have taken only zero samples; every other block has
//! z = (mean − exact) / s.e. with Bonferroni's correction at α = 0.01 over the blocks and
//! channels; the image mean is within 4 s.e. Every ray that reaches the light does so within 50
//! crossings, so a sample is at most 0.95^-46 ≈ 11 and the block means are close to normal.

use crate::common::*;
use hexray::scene::SceneDesc;
use hexray::transport::faults::Faults;
use hexray::transport::method::Method;

const SCENE: &str = "scenes/stability/mirror_corridor.json";
const SIZE: u32 = 64;
const SPP: u32 = 64;
const BLOCK: u32 = 8;
const ALPHA: f64 = 0.01;

/// An axis-aligned rectangle in a plane x = const: its y and z ranges.
#[derive(Clone, Copy, Debug)]
struct Rect {
    y: [f64; 2],
    z: [f64; 2],
}

/// The y and z ranges of the triangles of `material`.
fn extent(desc: &SceneDesc, material: &str) -> Rect {
    let mut r = Rect {
        y: [f64::MAX, f64::MIN],
        z: [f64::MAX, f64::MIN],
    };
    for t in desc.triangles.iter().filter(|t| t.material == material) {
        for v in t.v {
            r.y = [r.y[0].min(v[1]), r.y[1].max(v[1])];
            r.z = [r.z[0].min(v[2]), r.z[1].max(v[2])];
        }
    }
    r
}

/// The plane x = const of the triangles of `material`, the rectangle they cover (they are two
/// triangles of an axis-aligned rectangle in this scene) and the sign along x of their normals
/// (the emitting side of an emitter).
fn panel(desc: &SceneDesc, material: &str) -> (f64, Rect, f64) {
    let tris: Vec<_> = desc
        .triangles
        .iter()
        .filter(|t| t.material == material)
        .collect();
    assert_eq!(
        tris.len(),
        2,
        "{material}: one rectangle of two triangles expected"
    );
    let x = tris[0].v[0][0];
    let mut facing = [0.0; 2];
    for (k, t) in tris.iter().enumerate() {
        assert!(
            t.v.iter().all(|v| v[0] == x),
            "{material} is not in one plane x = const"
        );
        let e1 = [0, 1, 2].map(|i| t.v[1][i] - t.v[0][i]);
        let e2 = [0, 1, 2].map(|i| t.v[2][i] - t.v[0][i]);
        facing[k] = (e1[1] * e2[2] - e1[2] * e2[1]).signum();
    }
    assert_eq!(
        facing[0], facing[1],
        "{material}: triangles wound both ways"
    );
    (x, extent(desc, material), facing[0])
}

/// One crossing of an unfolded plane: its distance, its slope rectangle and the radiance seen.
#[derive(Clone, Copy, Debug)]
struct Event {
    dist: f64,
    a: [f64; 2],
    b: [f64; 2],
    value: f64,
}

/// Every crossing that can end a camera ray, nearest first, up to the one from which on the
/// emitter's slope rectangle lies inside the black square's.
fn events(desc: &SceneDesc) -> Vec<Event> {
    let mut mirrors: Vec<f64> = desc
        .triangles
        .iter()
        .filter(|t| t.material == "mirror")
        .map(|t| {
            assert!(
                t.v.iter().all(|v| v[0] == t.v[0][0]),
                "a mirror not in a plane x = const"
            );
            t.v[0][0]
        })
        .collect();
    mirrors.sort_by(f64::total_cmp);
    mirrors.dedup();
    assert_eq!(
        mirrors,
        [0.0, 1.0],
        "the unfolding below assumes mirrors at x = 0 and x = 1"
    );
    let (xl, light, facing) = panel(desc, "light");
    let (xb, black, _) = panel(desc, "black");
    let le = match &desc.materials["light"] {
        hexray::scene::MaterialDesc::Emitter { radiance, .. } if radiance[1..] == radiance[..2] => {
            radiance[0]
        }
        m => panic!("light is {m:?}, not a grey emitter"),
    };
    // A ray's |y| and |z| grow along its path, so one that reaches the panel was inside the
    // mirrors all the way: their edges (100 units out) cannot end a path before the light.
    let reach = extent(desc, "mirror");
    assert!(reach.y[0] <= light.y[0] && reach.y[1] >= light.y[1]);
    assert!(reach.z[0] <= light.z[0] && reach.z[1] >= light.z[1]);
    let xc = desc.camera.eye[0];
    // Crossings of the plane x = p, unfolded: going +x at p + 2m, going −x at 2 − p + 2m.
    let crossings = |p: f64, m: u32| {
        let m = 2.0 * m as f64;
        [(p + m - xc, 1.0), (2.0 - p + m - xc, -1.0)]
    };
    let slope = |r: Rect, d: f64| Event {
        dist: d,
        a: [r.y[0] / d, r.y[1] / d],
        b: [r.z[0] / d, r.z[1] / d],
        value: 0.0,
    };
    let first_black = (0..)
        .flat_map(|m| crossings(xb, m))
        .find(|&(d, _)| d > 0.0)
        .unwrap()
        .0;
    // The square is centred on the axis, so its later crossings are smaller squares inside the
    // first: only the first can end a ray.
    assert!(black.y[0] == -black.y[1] && black.z[0] == -black.z[1]);
    let square = slope(black, first_black);
    let inside = |e: &Event| {
        e.a[0] >= square.a[0]
            && e.a[1] <= square.a[1]
            && e.b[0] >= square.b[0]
            && e.b[1] <= square.b[1]
    };
    let mut out = vec![square];
    for m in 0.. {
        let mut done = true;
        for (d, dir) in crossings(xl, m) {
            if d <= 0.0 {
                continue;
            }
            let mut e = slope(light, d);
            if !inside(&e) {
                done = false;
            }
            // The front faces `facing` along x; a ray crossing against it sees the front.
            e.value = if dir * facing < 0.0 { le } else { 0.0 };
            out.push(e);
        }
        if done {
            break;
        }
    }
    out.sort_by(|p, q| p.dist.total_cmp(&q.dist));
    out
}

/// The radiance seen by the ray of slopes (a, b): that of the first event whose rectangle holds
/// it (0 when none does: the ray leaves the corridor). `events` are sorted by distance.
fn first_event<'a>(events: impl IntoIterator<Item = &'a Event>, a: f64, b: f64) -> f64 {
    events
        .into_iter()
        .find(|e| e.a[0] < a && a < e.a[1] && e.b[0] < b && b < e.b[1])
        .map_or(0.0, |e| e.value)
}

/// The radiance seen by the ray of slopes (a, b), found the long way: follow it in f64 from
/// plane to plane (mirrors, the panel's plane, the black square's plane), reflecting at the
/// mirrors, until it ends or can no longer reach the panel. 1 where it sees the panel's front.
fn trace_f64(desc: &SceneDesc, a: f64, b: f64) -> f64 {
    let (xl, light, facing) = panel(desc, "light");
    let (xb, black, _) = panel(desc, "black");
    let reach = extent(desc, "mirror");
    let within = |r: &Rect, y: f64, z: f64| r.y[0] < y && y < r.y[1] && r.z[0] < z && z < r.z[1];
    let (mut x, mut y, mut z, mut dir) = (desc.camera.eye[0], 0.0, 0.0, 1.0);
    loop {
        // The nearest plane ahead; a mirror turns the ray around.
        let (t, p) = [0.0, 1.0, xl, xb]
            .into_iter()
            .map(|p| ((p - x) / dir, p))
            .filter(|&(t, _)| t > 0.0)
            .min_by(|p, q| p.0.total_cmp(&q.0))
            .unwrap();
        (x, y, z) = (p, y + a * t, z + b * t);
        // |y| and |z| only grow: past the panel's range (or the mirrors') the ray is lost.
        let gone = |v: f64, slope: f64, r: [f64; 2]| {
            (slope >= 0.0 && v > r[1]) || (slope <= 0.0 && v < r[0])
        };
        if !within(&reach, y, z) || gone(y, a, light.y) || gone(z, b, light.z) {
            return 0.0;
        }
        if p == xl && within(&light, y, z) {
            return if dir * facing < 0.0 { 1.0 } else { 0.0 };
        }
        if p == xb && within(&black, y, z) {
            return 0.0;
        }
        if p == 0.0 || p == 1.0 {
            dir = -dir;
        }
    }
}

/// The exact expected image: per pixel, the share of its slope rectangle whose first event sees
/// the emitter's front, times Le.
fn exact_image(desc: &SceneDesc, width: u32, height: u32) -> Vec<[f64; 3]> {
    let cam = &desc.camera;
    assert!(
        cam.eye[1] == 0.0
            && cam.eye[2] == 0.0
            && cam.look_at[1] == 0.0
            && cam.look_at[2] == 0.0
            && cam.look_at[0] > cam.eye[0]
            && cam.up == [0.0, 0.0, 1.0],
        "the series assumes a camera on the axis looking along +x with up +z"
    );
    // Camera::ray: d = forward + sx right + sy up with right = forward x up = −y, so the slopes
    // are a = −sx · tan(vfov/2) · aspect and b = sy · tan(vfov/2).
    let t = (cam.vfov_deg.to_radians() * 0.5).tan();
    let (tr, tu) = (t * width as f64 / height as f64, t);
    let ev = events(desc);
    let mut img = Vec::with_capacity((width * height) as usize);
    for j in 0..height {
        for i in 0..width {
            let sx = [i, i + 1].map(|k| 2.0 * k as f64 / width as f64 - 1.0);
            let sy = [j + 1, j].map(|k| 1.0 - 2.0 * k as f64 / height as f64);
            let (a, b) = ([-sx[1] * tr, -sx[0] * tr], [sy[0] * tu, sy[1] * tu]);
            let hit: Vec<&Event> = ev
                .iter()
                .filter(|e| e.a[0] < a[1] && e.a[1] > a[0] && e.b[0] < b[1] && e.b[1] > b[0])
                .collect();
            let cuts = |lo: f64, hi: f64, edges: &mut dyn Iterator<Item = f64>| {
                let mut v: Vec<f64> = [lo, hi]
                    .into_iter()
                    .chain(edges.filter(|&x| x > lo && x < hi))
                    .collect();
                v.sort_by(f64::total_cmp);
                v.dedup();
                v
            };
            let xs = cuts(a[0], a[1], &mut hit.iter().flat_map(|e| e.a));
            let ys = cuts(b[0], b[1], &mut hit.iter().flat_map(|e| e.b));
            let mut lit = 0.0;
            for u in xs.windows(2) {
                for v in ys.windows(2) {
                    let (cu, cv) = (0.5 * (u[0] + u[1]), 0.5 * (v[0] + v[1]));
                    lit += first_event(hit.iter().copied(), cu, cv) * (u[1] - u[0]) * (v[1] - v[0]);
                }
            }
            img.push([lit / ((a[1] - a[0]) * (b[1] - b[0])); 3]);
        }
    }
    img
}

fn blocks(x: u32, y: u32) -> Option<usize> {
    Some(((y / BLOCK) * (SIZE / BLOCK) + x / BLOCK) as usize)
}

fn compare(film: &hexray::film::Film) -> TruthReport {
    let (scene, _) = load(SCENE);
    let exact = exact_image(&scene.desc, SIZE, SIZE);
    against_truth(film, &exact, blocks, ALPHA)
}

/// The corridor rendered with `method` on `backend` against the series: path tracing with seed
/// 30 on the CPU, 31 on the GPU; BDPT with 32 and 33.
fn report(backend: Backend, method: Method, faults: Faults) -> TruthReport {
    let seed = match (method, backend) {
        (Method::Bdpt, Backend::Cpu) => 32,
        (Method::Bdpt, Backend::Gpu) => 33,
        (_, Backend::Cpu) => 30,
        (_, Backend::Gpu) => 31,
    };
    compare(
        &Render::file(SCENE)
            .size(SIZE, SIZE)
            .spp(SPP)
            .seed(seed)
            .method(method)
            .faults(faults)
            .on(backend),
    )
}

const DEPTH_CAP: Faults = Faults {
    max_bounces: 8,
    ..Faults::NONE
};
const DIM_MIRROR: Faults = Faults {
    specular_scale: 0.97,
    ..Faults::NONE
};

/// The unfolding is right: at 10^5 directions spread uniformly over the image, the first event of
/// the series sees what following the ray through the corridor in f64 sees (exactly: a direction
/// that grazes an edge has probability 0), and the share of them that see the light matches the
/// exact image mean within 4 binomial s.e.
#[test]
fn mirror_corridor_unfolding_matches_tracing_in_f64() {
    let (scene, _) = load(SCENE);
    let ev = events(&scene.desc);
    let t = (scene.desc.camera.vfov_deg.to_radians() * 0.5).tan();
    let (mut lit, mut differ) = (0, 0);
    for i in 0..100_000u32 {
        let u = hexray::math::sampling::Sampler::new(40, i, 0).draw4(0);
        let (a, b) = ((2.0 * u[0] as f64 - 1.0) * t, (2.0 * u[1] as f64 - 1.0) * t);
        let want = trace_f64(&scene.desc, a, b);
        lit += (want > 0.0) as u32;
        differ += ((first_event(&ev, a, b) > 0.0) != (want > 0.0)) as u32;
    }
    assert_eq!(differ, 0, "{differ} of 10^5 directions disagree");
    // And the pixel areas add up: the share of those uniform directions that see the light
    // estimates the exact image mean (binomial s.e.).
    let exact = exact_image(&scene.desc, SIZE, SIZE);
    let mean = exact.iter().map(|p| p[0]).sum::<f64>() / exact.len() as f64;
    let share = lit as f64 / 1e5;
    let se = (share * (1.0 - share) / 1e5).sqrt();
    assert!(
        (share - mean).abs() <= 4.0 * se && lit > 10_000,
        "{lit} of 10^5 directions see the light, the exact image mean is {mean}"
    );
}

on_each_backend! {
    fn mirror_corridor_matches_the_series(backend) {
        let r = report(backend, Method::Path, Faults::NONE);
        r.assert_agrees(&format!("{backend} mirror corridor"));
    }

    /// Power: a maximum depth of 8 bounces loses every crossing from the 9th on.
    fn mirror_corridor_rejects_a_depth_cap(backend) {
        let r = report(backend, Method::Path, DEPTH_CAP);
        r.assert_rejected_as_too_dark(&format!("{backend} mirror corridor, depth cap 8"));
    }

    /// ... and mirrors that reflect 97 % (0.97^k at crossing k).
    fn mirror_corridor_rejects_a_dim_mirror(backend) {
        let r = report(backend, Method::Path, DIM_MIRROR);
        r.assert_rejected_as_too_dark(&format!("{backend} mirror corridor, mirror 0.97"));
    }
}

// BDPT: the corridor's mirrors are specular, so no light vertex is stored and no connection is
// possible through them: the image comes from camera subpaths that hit the light (s = 0) and
// from next-event estimation where a camera vertex is diffuse, weighted by MIS, and must match
// the same series; a depth cap of 8 must be rejected the same way.

on_each_backend! {
    fn mirror_corridor_matches_the_series_with_bdpt(backend) {
        let r = report(backend, Method::Bdpt, Faults::NONE);
        r.assert_agrees(&format!("{backend} BDPT mirror corridor"));
    }

    fn mirror_corridor_rejects_a_depth_cap_with_bdpt(backend) {
        let r = report(backend, Method::Bdpt, DEPTH_CAP);
        r.assert_rejected_as_too_dark(&format!("{backend} BDPT mirror corridor, depth cap 8"));
    }
}
