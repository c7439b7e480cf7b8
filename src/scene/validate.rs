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
    check_vec(&cam.eye, &cp.key("eye"))?;
    check_vec(&cam.look_at, &cp.key("look_at"))?;
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

    // Triangles: finite vertices, a material that exists, a non-zero area in f32.
    let tp = root.key("triangles");
    for (i, t) in desc.triangles.iter().enumerate() {
        let p = tp.index(i);
        for (k, v) in t.v.iter().enumerate() {
            check_vec(v, &p.key("v").index(k))?;
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
    }

    // Spheres: finite centre, positive radius, a material that exists, an emitter's area > 0.
    let sp = root.key("spheres");
    for (i, s) in desc.spheres.iter().enumerate() {
        let p = sp.index(i);
        check_vec(&s.center, &p.key("center"))?;
        if !(finite_f32(s.radius) && s.radius > 0.0) {
            return Err(issue(
                p.key("radius"),
                format!("radius {} is not > 0", s.radius),
                "give the sphere a positive radius",
            ));
        }
        check_material_ref(&s.material, &p.key("material"), desc)?;
        // An emitting sphere is sampled by area: 4 pi r^2 must be > 0 in f32, as the emitter
        // table computes it.
        let emits = matches!(
            desc.materials.get(&s.material),
            Some(MaterialDesc::Emitter { .. })
        );
        let radius = s.radius as f32;
        if emits && 4.0 * std::f32::consts::PI * radius * radius == 0.0 {
            return Err(issue(
                p.key("radius"),
                format!(
                    "an emitting sphere of radius {} has zero area in f32",
                    s.radius
                ),
                "give the light a radius whose square is a normal 32-bit float (> 1e-19)",
            ));
        }
    }

    // Boxes: finite corners with min < max on every axis.
    let bp = root.key("boxes");
    for (i, b) in desc.boxes.iter().enumerate() {
        let p = bp.index(i);
        check_vec(&b.min, &p.key("min"))?;
        check_vec(&b.max, &p.key("max"))?;
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
    let emits = |name: &str| {
        matches!(desc.materials.get(name),
            Some(MaterialDesc::Emitter { radiance, .. }) if radiance.iter().any(|&x| x > 0.0))
    };
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
