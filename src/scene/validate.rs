//! Everything that makes a parsed scene unrenderable, found before any rendering starts.
//!
//! Each check returns the path of the offending value and a sentence saying what to do; the
//! caller turns the path into a line and column of the file.

use super::format::{MaterialDesc, Scale, SceneDesc};
use super::locate::JsonPath;

/// One problem: where, what, and what to do.
#[derive(Debug, Clone)]
pub struct Issue {
    pub path: JsonPath,
    pub message: String,
    pub help: String,
}

fn issue(path: JsonPath, message: impl Into<String>, help: impl Into<String>) -> Issue {
    Issue {
        path,
        message: message.into(),
        help: help.into(),
    }
}

/// Finite as f32: the renderer computes in f32, so 1e39 is as unusable as infinity.
fn finite_f32(x: f64) -> bool {
    x.is_finite() && (x as f32).is_finite()
}

fn check_vec(v: &[f64; 3], path: &JsonPath) -> Result<(), Issue> {
    for (i, &x) in v.iter().enumerate() {
        if !finite_f32(x) {
            return Err(issue(
                path.index(i),
                format!("{x} is not a finite 32-bit float"),
                "use a finite number with magnitude below 3.4e38",
            ));
        }
    }
    Ok(())
}

/// The largest coordinate magnitude (and sphere radius) accepted. The integrators form
/// products of two squared distances in f32 (a solid-angle pdf times an area, the MIS weights'
/// pdf ratios), so the scene's extent squared, squared again, must stay below f32's 3.4e38:
/// (2e9 * sqrt 3)^4 is 1.4e38.
pub const MAX_COORDINATE: f64 = 1e9;
/// Coordinates up to this magnitude are covered by the precision tests (docs/stability.md);
/// beyond it a scene renders with a warning.
pub const TESTED_COORDINATE: f64 = 1e5;
/// Emitted radiance per channel is 0 or within these bounds: a path's throughput multiplies
/// it by factors of either sign of exponent, and f32 must carry the product (1e-46 is 0 in
/// f32, and 1.2e38 overflows at the first such factor, so every sample would be dropped).
pub const MIN_RADIANCE: f64 = 1e-30;
pub const MAX_RADIANCE: f64 = 1e30;

/// A point: finite in f32 and within [`MAX_COORDINATE`] of the origin on every axis.
fn check_point(v: &[f64; 3], path: &JsonPath) -> Result<(), Issue> {
    check_vec(v, path)?;
    if let Some(i) = v.iter().position(|x| x.abs() > MAX_COORDINATE) {
        return Err(issue(
            path.index(i),
            format!(
                "coordinate {:e} is beyond +-{MAX_COORDINATE:e}, where squared distances overflow \
                 32-bit floats",
                v[i]
            ),
            "scale the scene down or move it nearer the origin (the renderer is tested to 1e5)",
        ));
    }
    Ok(())
}

/// The largest coordinate magnitude in the scene's geometry and camera.
pub fn extent(desc: &SceneDesc) -> f64 {
    let pts = desc
        .triangles
        .iter()
        .flat_map(|t| t.v.iter())
        .chain(desc.spheres.iter().map(|s| &s.center))
        .chain(desc.boxes.iter().flat_map(|b| [&b.min, &b.max]))
        .chain([&desc.camera.eye, &desc.camera.look_at]);
    let spheres = desc
        .spheres
        .iter()
        .map(|s| s.center.iter().fold(0.0f64, |m, x| m.max(x.abs())) + s.radius);
    pts.map(|p| p.iter().fold(0.0f64, |m, x| m.max(x.abs())))
        .chain(spheres)
        .fold(0.0, f64::max)
}

/// An emitter's area as the emitter table computes it in f32 must be a normal number: its
/// reciprocal is the area pdf of every light sample on it.
fn check_emitter_area(area: f32, path: JsonPath, what: &str) -> Result<(), Issue> {
    if area.is_finite() && area >= f32::MIN_POSITIVE {
        return Ok(());
    }
    Err(issue(
        path,
        format!("this emitting {what} has area {area:e} in f32, too small to sample"),
        "make the light larger (its area must exceed 1.2e-38 in 32-bit floats), or scale the \
         whole scene up",
    ))
}

fn check_unit_rgb(v: &[f64; 3], path: &JsonPath, what: &str) -> Result<(), Issue> {
    check_vec(v, path)?;
    for (i, &x) in v.iter().enumerate() {
        if !(0.0..=1.0).contains(&x) {
            return Err(issue(
                path.index(i),
                format!("{what} {x} is outside [0, 1]"),
                format!(
                    "a {what} is a fraction of light kept; values above 1 create energy. \
                     Use a value in [0, 1]"
                ),
            ));
        }
    }
    Ok(())
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Whether a triangle, as the renderer sees it (in f32), has no usable normal: the sine of the
/// angle between its edges is below f32 resolution, so the normal would be noise (or zero, for
/// repeated or collinear vertices). Inline triangles that are degenerate are errors; mesh
/// triangles are dropped and counted.
pub fn degenerate_f32(v: [[f32; 3]; 3]) -> bool {
    let v = v.map(|p| p.map(f64::from));
    let (e1, e2) = (sub(v[1], v[0]), sub(v[2], v[0]));
    norm(cross(e1, e2)) <= 4.0 * f32::EPSILON as f64 * norm(e1) * norm(e2)
}

/// The material names closest to `name` (edit distance), for "did you mean".
fn suggest(name: &str, desc: &SceneDesc) -> String {
    let best = desc
        .materials
        .keys()
        .map(|k| (strsim::damerau_levenshtein(name, k), k))
        .min();
    match best {
        Some((d, k)) if d <= (name.len().max(k.len()) / 2).max(2) => {
            format!("did you mean `{k}`? ")
        }
        _ => String::new(),
    }
}

/// Resolves a material reference.
fn check_material_ref(name: &str, path: &JsonPath, desc: &SceneDesc) -> Result<(), Issue> {
    let known: Vec<&str> = desc.materials.keys().map(String::as_str).collect();
    match desc.materials.get(name) {
        None => Err(issue(
            path.clone(),
            format!("unknown material `{name}`"),
            format!(
                "{}the materials defined in `materials` are: {}",
                suggest(name, desc),
                known.join(", ")
            ),
        )),
        Some(_) => Ok(()),
    }
}

pub fn validate(desc: &SceneDesc) -> Result<(), Issue> {
    let root = JsonPath::root();

    // Camera: a finite, non-degenerate pinhole.
    let cam = &desc.camera;
    let cp = root.key("camera");
    check_point(&cam.eye, &cp.key("eye"))?;
    check_point(&cam.look_at, &cp.key("look_at"))?;
    check_vec(&cam.up, &cp.key("up"))?;
    if !(cam.vfov_deg.is_finite() && cam.vfov_deg > 0.0 && cam.vfov_deg < 180.0) {
        return Err(issue(
            cp.key("vfov_deg"),
            format!(
                "vertical field of view {} is outside (0, 180)",
                cam.vfov_deg
            ),
            "give the vertical field of view in degrees, e.g. 40 or 90",
        ));
    }
    let view = sub(cam.look_at, cam.eye);
    if norm(view) == 0.0 {
        return Err(issue(
            cp.key("look_at"),
            "look_at equals eye, so there is no view direction",
            "move look_at to a point in front of the camera",
        ));
    }
    if norm(cam.up) == 0.0 || norm(cross(view, cam.up)) <= 1e-6 * norm(view) * norm(cam.up) {
        return Err(issue(
            cp.key("up"),
            "up is zero or parallel to the view direction (look_at - eye)",
            "choose an up vector perpendicular to the view, e.g. [0, 0, 1] for a horizontal view",
        ));
    }

    // Materials: physically meaningful parameters.
    let mp = root.key("materials");
    for (name, m) in &desc.materials {
        let p = mp.key(name);
        match m {
            MaterialDesc::Diffuse { albedo } => check_unit_rgb(albedo, &p.key("albedo"), "albedo")?,
            MaterialDesc::Mirror { reflectance } => {
                check_unit_rgb(reflectance, &p.key("reflectance"), "reflectance")?
            }
            MaterialDesc::Glass { ior, tint } => {
                if !(finite_f32(*ior) && *ior > 0.0) {
                    return Err(issue(
                        p.key("ior"),
                        format!("index of refraction {ior} is not > 0"),
                        "use the medium's index of refraction, e.g. 1.5 for glass, 1.33 for water",
                    ));
                }
                check_unit_rgb(tint, &p.key("tint"), "tint")?;
            }
            MaterialDesc::Emitter {
                radiance,
                one_sided,
                albedo,
            } => {
                check_vec(radiance, &p.key("radiance"))?;
                if let Some(i) = radiance.iter().position(|&x| x < 0.0) {
                    return Err(issue(
                        p.key("radiance").index(i),
                        format!("radiance {} is negative", radiance[i]),
                        "emitted radiance is >= 0 in every channel",
                    ));
                }
                if let Some(i) = radiance.iter().position(|&x| {
                    x != 0.0 && !(MIN_RADIANCE as f32..=MAX_RADIANCE as f32).contains(&(x as f32))
                }) {
                    return Err(issue(
                        p.key("radiance").index(i),
                        format!(
                            "radiance {:e} is outside [{MIN_RADIANCE:e}, {MAX_RADIANCE:e}], the \
                             range a path's 32-bit throughput carries (0 is allowed)",
                            radiance[i]
                        ),
                        "scale the lights into that range and set the image's brightness with \
                         --exposure",
                    ));
                }
                if !one_sided {
                    return Err(issue(
                        p.key("one_sided"),
                        "two-sided emitters are not modelled",
                        "remove `one_sided` or set it to true; for light on both sides use two \
                         triangles wound in opposite directions",
                    ));
                }
                check_unit_rgb(albedo, &p.key("albedo"), "albedo")?;
            }
        }
    }

    // Whether a material emits (after the materials' checks, its radiance is 0 or normal).
    let emits = |name: &str| {
        matches!(desc.materials.get(name),
            Some(MaterialDesc::Emitter { radiance, .. }) if radiance.iter().any(|&x| x > 0.0))
    };

    // Triangles: finite vertices, a material that exists, a non-zero area in f32.
    let tp = root.key("triangles");
    for (i, t) in desc.triangles.iter().enumerate() {
        let p = tp.index(i);
        for (k, v) in t.v.iter().enumerate() {
            check_point(v, &p.key("v").index(k))?;
        }
        check_material_ref(&t.material, &p.key("material"), desc)?;
        // The renderer sees the vertices rounded to f32: a triangle far from the origin can
        // collapse there although its f64 vertices are distinct.
        if degenerate_f32(t.v.map(|p| p.map(|x| x as f32))) {
            return Err(issue(
                p.key("v"),
                "the triangle has zero area at f32 precision (repeated or collinear vertices, \
                 or too small for its distance from the origin)",
                "remove it, correct a vertex, or move the scene nearer the origin",
            ));
        }
        if emits(&t.material) {
            let f = t.v.map(|p| glam::Vec3::from(p.map(|x| x as f32)));
            let area = 0.5 * (f[1] - f[0]).cross(f[2] - f[0]).length();
            check_emitter_area(area, p.key("v"), "triangle")?;
        }
    }

    // Spheres: finite centre, positive radius, a material that exists, an emitter's area > 0.
    let sp = root.key("spheres");
    for (i, s) in desc.spheres.iter().enumerate() {
        let p = sp.index(i);
        check_point(&s.center, &p.key("center"))?;
        if !(finite_f32(s.radius) && s.radius > 0.0 && s.radius <= MAX_COORDINATE) {
            return Err(issue(
                p.key("radius"),
                if s.radius > MAX_COORDINATE {
                    format!("radius {:e} is beyond {MAX_COORDINATE:e}", s.radius)
                } else {
                    format!("radius {} is not > 0", s.radius)
                },
                "give the sphere a positive radius, at most 1e9",
            ));
        }
        check_material_ref(&s.material, &p.key("material"), desc)?;
        // An emitting sphere is sampled by area: 4 pi r^2 must be > 0 in f32, as the emitter
        // table computes it.
        let radius = s.radius as f32;
        if emits(&s.material) {
            let area = 4.0 * std::f32::consts::PI * radius * radius;
            check_emitter_area(area, p.key("radius"), "sphere")?;
        }
    }

    // Boxes: finite corners with min < max on every axis.
    let bp = root.key("boxes");
    for (i, b) in desc.boxes.iter().enumerate() {
        let p = bp.index(i);
        check_point(&b.min, &p.key("min"))?;
        check_point(&b.max, &p.key("max"))?;
        // Compared as the renderer sees them, rounded to f32: a thin box far from the origin
        // can flatten there.
        if let Some(a) = (0..3).find(|&a| b.min[a] as f32 >= b.max[a] as f32) {
            return Err(issue(
                p.key("max").index(a),
                format!(
                    "max {} is not greater than min {} on axis {} (at f32 precision)",
                    b.max[a],
                    b.min[a],
                    ["x", "y", "z"][a]
                ),
                "a box needs min < max on every axis; a thin box far from the origin needs more \
                 thickness or a position nearer the origin",
            ));
        }
        check_material_ref(&b.material, &p.key("material"), desc)?;
        if emits(&b.material) {
            let d = [0, 1, 2].map(|a| b.max[a] as f32 - b.min[a] as f32);
            let smallest = (d[0] * d[1]).min(d[1] * d[2]).min(d[0] * d[2]);
            check_emitter_area(smallest, p.key("max"), "box face")?;
        }
    }

    // Meshes: a file named, a material that exists, a usable transform. The files themselves
    // are read after validation (`Scene::from_json`).
    let mp = root.key("meshes");
    for (i, m) in desc.meshes.iter().enumerate() {
        let p = mp.index(i);
        if m.file.trim().is_empty() {
            return Err(issue(
                p.key("file"),
                "the mesh file name is empty",
                "give the path of a .ply or .obj file, relative to the scene file's folder",
            ));
        }
        check_material_ref(&m.material, &p.key("material"), desc)?;
        if let Some(scale) = m.scale {
            let values: Vec<(JsonPath, f64)> = match scale {
                Scale::Uniform(s) => vec![(p.key("scale"), s)],
                Scale::PerAxis(v) => (0..3).map(|k| (p.key("scale").index(k), v[k])).collect(),
            };
            for (path, s) in values {
                if !finite_f32(s) || s == 0.0 {
                    return Err(issue(
                        path,
                        format!("scale {s} is not a finite nonzero number"),
                        "a scale is a nonzero factor, e.g. 0.5 or [1, 1, 2]; 1 keeps the size",
                    ));
                }
            }
        }
        if let Some(r) = &m.rotate {
            let rp = p.key("rotate");
            check_vec(&r.axis, &rp.key("axis"))?;
            if norm(r.axis) == 0.0 {
                return Err(issue(
                    rp.key("axis"),
                    "the rotation axis is zero",
                    "give the axis as a nonzero direction, e.g. [0, 0, 1]",
                ));
            }
            if !r.degrees.is_finite() {
                return Err(issue(
                    rp.key("degrees"),
                    format!("{} degrees is not a finite angle", r.degrees),
                    "give the angle in degrees, e.g. 90",
                ));
            }
        }
        if let Some(t) = &m.translate {
            check_vec(t, &p.key("translate"))?;
        }
    }

    // At least one primitive that emits light, or the image is black by construction.
    if !desc.triangles.iter().any(|t| emits(&t.material))
        && !desc.boxes.iter().any(|b| emits(&b.material))
        && !desc.spheres.iter().any(|s| emits(&s.material))
        && !desc.meshes.iter().any(|m| emits(&m.material))
    {
        return Err(issue(
            root.key("triangles"),
            "the scene has no emitter: no triangle, box or sphere uses an emitter material with \
             radiance > 0",
            "add a light: triangles whose material has \"type\": \"emitter\" and a positive \
             radiance, wound so that (v1 - v0) x (v2 - v0) faces the scene, or a sphere of that \
             material",
        ));
    }
    Ok(())
}

/// Emitted radiance that the methods tracing light subpaths (light, bdpt, sppm, vcm) can
/// carry: they sum splats in 64-bit fixed point (`splat.rs`: resolution 6e-8, range 1.1e12),
/// so a splat must neither overflow (measured on cornell_box: radiance 1e10 keeps every sample,
/// 1e15 drops 60 %) nor round away (a light of 1e-20 would splat nothing and leave the image
/// black without a word).
pub const SPLAT_RADIANCE: (f64, f64) = (1e-3, 1e9);

/// Refuses, for the splatting methods, an emitter whose radiance is outside [`SPLAT_RADIANCE`].
pub fn check_splat_range(desc: &SceneDesc, method: &str) -> Result<(), Issue> {
    let (lo, hi) = SPLAT_RADIANCE;
    for (name, m) in &desc.materials {
        if let MaterialDesc::Emitter { radiance, .. } = m {
            if let Some(i) = radiance
                .iter()
                .position(|&x| x != 0.0 && !(lo..=hi).contains(&x))
            {
                return Err(issue(
                    JsonPath::root()
                        .key("materials")
                        .key(name)
                        .key("radiance")
                        .index(i),
                    format!(
                        "radiance {:e} is outside [{lo:e}, {hi:e}], the range --method {method} \
                         sums exactly (its light splats are 64-bit fixed point)",
                        radiance[i]
                    ),
                    "scale the lights into that range and set the brightness with --exposure, \
                     or render with --method path",
                ));
            }
        }
    }
    Ok(())
}
