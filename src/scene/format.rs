//! The scene file format: the JSON of `scenes/*.json`, as serde structs.
//!
//! Unknown fields are rejected everywhere, so a misspelt key is an error with its location
//! rather than a silently ignored setting. Numbers are read as f64 and checked to fit f32
//! (the renderer's precision) by [`super::validate`].

use serde::Deserialize;
use std::collections::BTreeMap;

/// A whole scene: one pinhole camera, named materials, and the geometry that uses them.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// The scene's name, for logs and output metadata.
    #[serde(default)]
    pub name: String,
    /// Where the scene comes from (free text, not used by the renderer).
    #[serde(default)]
    pub seed: Option<String>,
    /// Conventions the scene assumes (free text, not used by the renderer).
    #[serde(default)]
    pub notes: Vec<String>,
    /// The pinhole camera.
    pub camera: CameraDesc,
    /// Materials by name; geometry refers to them by these names.
    pub materials: BTreeMap<String, MaterialDesc>,
    /// Triangles, each with its own three vertices.
    #[serde(default)]
    pub triangles: Vec<TriangleDesc>,
    /// Spheres.
    #[serde(default)]
    pub spheres: Vec<SphereDesc>,
    /// Axis-aligned boxes, each expanded to 12 outward-facing triangles.
    #[serde(default)]
    pub boxes: Vec<BoxDesc>,
}

/// A pinhole camera; images are as wide as `--width` and as tall as `--height`, with square
/// pixels, so the horizontal field of view follows from the aspect ratio.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// The centre of projection.
    pub eye: [f64; 3],
    /// A point the camera looks at (on the optical axis).
    pub look_at: [f64; 3],
    /// The world direction that appears upward in the image; must not be parallel to the view.
    pub up: [f64; 3],
    /// Vertical field of view in degrees, in (0, 180).
    pub vfov_deg: f64,
    /// A note for people (e.g. which world direction is image left); not used by the renderer.
    #[serde(default)]
    pub note: Option<String>,
}

/// The four material kinds. `type` selects the kind; each kind takes only its own fields.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum MaterialDesc {
    /// Two-sided Lambertian reflector.
    Diffuse {
        /// Linear RGB reflectance (the hemispherical albedo), each channel in [0, 1].
        albedo: [f64; 3],
    },
    /// Perfect specular reflector.
    Mirror {
        /// Linear RGB reflectance, each channel in [0, 1].
        reflectance: [f64; 3],
    },
    /// Smooth dielectric: exact unpolarised Fresnel, total internal reflection.
    Glass {
        /// Index of refraction inside (outside is 1.0); must be > 0.
        ior: f64,
        /// Multiplies the light at each refraction, each channel in [0, 1]; default white.
        #[serde(default = "white")]
        tint: [f64; 3],
    },
    /// One-sided area light: emits on the side of (v1 - v0) x (v2 - v0), black behind.
    Emitter {
        /// Emitted linear RGB radiance, each channel >= 0.
        radiance: [f64; 3],
        /// Must be true when given: two-sided emitters are not modelled.
        #[serde(default = "yes")]
        one_sided: bool,
        /// Optional Lambertian reflectance of the emitting surface (default black), each
        /// channel in [0, 1]; the furnace tests use emitters that also reflect.
        #[serde(default)]
        albedo: [f64; 3],
    },
}

fn white() -> [f64; 3] {
    [1.0; 3]
}
fn yes() -> bool {
    true
}

/// One triangle. Its winding fixes the emitting side of an emitter.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TriangleDesc {
    /// The three vertices.
    pub v: [[f64; 3]; 3],
    /// The name of a material in `materials`.
    pub material: String,
    /// A human label (e.g. "wall AB"); not used by the renderer.
    #[serde(default)]
    pub part: Option<String>,
}

/// One sphere.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereDesc {
    /// Centre.
    pub center: [f64; 3],
    /// Radius, > 0.
    pub radius: f64,
    /// The name of a material in `materials`; an emitter makes the sphere an area light.
    pub material: String,
    /// Normals point inward (Mitsuba's `flip_normals`): an emitting sphere then lights its
    /// inside, and a glass sphere becomes a bubble of air in glass.
    #[serde(default)]
    pub flip_normals: bool,
}

/// An axis-aligned box, expanded to 12 triangles whose normals face outward.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxDesc {
    /// The minimum corner.
    pub min: [f64; 3],
    /// The maximum corner; strictly greater than `min` on every axis.
    pub max: [f64; 3],
    /// The name of a material in `materials`.
    pub material: String,
}

impl BoxDesc {
    /// The 12 triangles of the box, wound so that (v1 - v0) x (v2 - v0) points out of the box.
    pub fn triangles(&self) -> [[[f64; 3]; 3]; 12] {
        let (a, b) = (self.min, self.max);
        // Corner k has x from bit 0, y from bit 1, z from bit 2.
        let c = |k: usize| {
            [
                if k & 1 == 0 { a[0] } else { b[0] },
                if k & 2 == 0 { a[1] } else { b[1] },
                if k & 4 == 0 { a[2] } else { b[2] },
            ]
        };
        // Each face as a quad (p0, p1, p2, p3) counter-clockwise seen from outside.
        const FACES: [[usize; 4]; 6] = [
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
        ];
        let mut out = [[[0.0; 3]; 3]; 12];
        for (f, q) in FACES.iter().enumerate() {
            out[2 * f] = [c(q[0]), c(q[1]), c(q[2])];
            out[2 * f + 1] = [c(q[0]), c(q[2]), c(q[3])];
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_triangles_face_outward() {
        let bx = BoxDesc {
            min: [1.0, 2.0, 3.0],
            max: [2.0, 4.0, 7.0],
            material: "m".into(),
        };
        let centre = [1.5, 3.0, 5.0];
        for t in bx.triangles() {
            let e1: Vec<f64> = (0..3).map(|i| t[1][i] - t[0][i]).collect();
            let e2: Vec<f64> = (0..3).map(|i| t[2][i] - t[0][i]).collect();
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            let out: f64 = (0..3).map(|i| n[i] * (t[0][i] - centre[i])).sum();
            assert!(out > 0.0, "triangle {t:?} faces inward");
        }
    }
}
